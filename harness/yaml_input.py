"""YAML from untrusted configs: safe types only, no duplicate keys, no alias bomb, and no number
that YAML 1.1 reads otherwise than it looks (``010`` is 8, ``1:30`` is 90); ``1e-3`` is a
number (YAML 1.1 made it text).

``yaml.safe_load`` builds shared nodes for aliases, but anything that walks the result (validation,
JSON for run.json, an error message) expands them: a few hundred bytes of nested aliases expand to
billions of nodes. `load` refuses a document with more than ``MAX_ALIASES`` alias uses or whose
expanded size exceeds ``MAX_NODES`` nodes, before constructing anything.
"""
from __future__ import annotations

import re

import yaml

MAX_ALIASES = 200
MAX_NODES = 200_000


class _Loader(yaml.SafeLoader):
    def __init__(self, stream):
        super().__init__(stream)
        self._aliases = 0

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            self._aliases += 1
            if self._aliases > MAX_ALIASES:
                raise yaml.YAMLError(f"more than {MAX_ALIASES} aliases (*name): refused")
        return super().compose_node(parent, index)


# YAML 1.1 reads `1e-3` and `1E5` (no dot, or no exponent sign) as text; a config means the number.
# Without a dot only short forms (up to 3 digits each side): a 12-hex case id such as
# 123e45678901 stays text.
_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:(?:[0-9][0-9_]*\.[0-9_]*|\.[0-9_]+)[eE][-+]?[0-9]+|[0-9]{1,3}[eE][-+]?[0-9]{1,3})$"),
    list("-+0123456789."))


class _TooBig(yaml.YAMLError):
    """More values than a config may hold (`_too_big`)."""


def _too_big(text: str) -> None:
    """`yaml.YAMLError` when the document holds, aliases expanded, more than ``MAX_NODES`` values,
    counted on libyaml's event stream (C speed) before any Python node is built: a long plain
    list is refused in seconds, with a message that says whether aliases made it so."""
    loader = getattr(yaml, "CSafeLoader", None)
    if loader is None:
        return                      # no libyaml: the node walk (`_expanded_size`) bounds it
    size: dict = {}                 # anchor -> its expanded size
    stack = [[0, None]]             # open collections: [values so far, anchor]
    total, aliases = 0, 0           # values so far, aliases expanded
    try:
        for ev in yaml.parse(text, Loader=loader):
            if isinstance(ev, (yaml.SequenceStartEvent, yaml.MappingStartEvent)):
                stack.append([1, ev.anchor])
                total += 1
            elif isinstance(ev, (yaml.SequenceEndEvent, yaml.MappingEndEvent)):
                n, anchor = stack.pop()
                if anchor is not None:
                    size[anchor] = n
                stack[-1][0] += n
            elif isinstance(ev, (yaml.ScalarEvent, yaml.AliasEvent)):
                alias = isinstance(ev, yaml.AliasEvent)
                aliases += alias
                n = size.get(ev.anchor, 1) if alias else 1
                if not alias and ev.anchor is not None:
                    size[ev.anchor] = 1
                stack[-1][0] += n
                total += n
            if total > MAX_NODES:
                why = (f"with its {aliases} alias(es) expanded" if aliases else "a config holds at most that many")
                raise _TooBig(f"the document holds more than {MAX_NODES:,} values ({why}): refused")
    except _TooBig:
        raise
    except yaml.YAMLError:
        return                      # a syntax error: the Python loader reports it with its line


def _expanded_size(node, memo: dict, stack: set) -> int:
    key = id(node)
    if key in memo:
        return memo[key]
    if key in stack:
        raise yaml.YAMLError("a recursive alias: refused")
    stack.add(key)
    if isinstance(node, yaml.SequenceNode):
        n = 1 + sum(_expanded_size(v, memo, stack) for v in node.value)
    elif isinstance(node, yaml.MappingNode):
        n = 1 + sum(_expanded_size(k, memo, stack) + _expanded_size(v, memo, stack) for k, v in node.value)
    else:
        n = 1
    stack.discard(key)
    memo[key] = n
    if n > MAX_NODES:
        raise yaml.YAMLError(f"the document expands to more than {MAX_NODES:,} values (alias bomb?): refused")
    return n


def _duplicate_keys(node, out: list, done: set, construct) -> None:
    """Messages for every key that appears twice in one mapping (the last would silently win: a
    whole task or setting lost), walking each node once. Keys compare as the values they load
    as (``construct``), as the loaded dict would: ``1``, ``1.0`` and ``0x1`` are the same key,
    ``1`` and ``"1"`` are not."""
    if id(node) in done:
        return
    done.add(id(node))
    if isinstance(node, yaml.MappingNode):
        seen: dict = {}
        for k, v in node.value:
            if isinstance(k, yaml.ScalarNode) and k.tag != "tag:yaml.org,2002:merge":
                try:
                    key = ("value", construct(k))     # equal as loaded (1, 1.0, 0x1, true): one dict key
                    hash(key)
                except Exception:  # noqa: BLE001 - a key that does not load is reported when the document is built
                    key = ("text", k.value)
                if key in seen:
                    out.append(f"duplicate key {k.value!r} at line {k.start_mark.line + 1} (first at line "
                               f"{seen[key] + 1})")
                else:
                    seen[key] = k.start_mark.line
            _duplicate_keys(v, out, done, construct)
    elif isinstance(node, yaml.SequenceNode):
        for v in node.value:
            _duplicate_keys(v, out, done, construct)


_INT, _FLOAT = "tag:yaml.org,2002:int", "tag:yaml.org,2002:float"


def _nodes(node):
    """Every node of the document once (an alias is the node it names), in document order: a
    mapping's keys and values, a sequence's items, each before what it holds."""
    done, stack = set(), [node]
    while stack:
        n = stack.pop()
        if id(n) in done:
            continue
        done.add(id(n))
        yield n
        if isinstance(n, yaml.SequenceNode):
            stack.extend(reversed(n.value))
        elif isinstance(n, yaml.MappingNode):
            for k, v in reversed(n.value):
                stack.extend((v, k))


def _yaml11_numbers(node, out: list) -> None:
    """Messages for plain numbers YAML 1.1 reads otherwise than they look: a leading zero is
    octal (``010`` is 8) and colons are base 60 (``1:30`` is 90)."""
    for n in _nodes(node):
        if isinstance(n, yaml.ScalarNode) and n.style is None and n.tag in (_INT, _FLOAT):
            t = n.value.lstrip("+-").replace("_", "")
            why = ("is octal" if n.tag == _INT and len(t) > 1 and t[0] == "0" and t.isdigit()
                   else "is base 60" if ":" in t else None)
            if why:
                value = yaml.constructor.SafeConstructor().construct_object(n)
                out.append(f"{n.value!r} at line {n.start_mark.line + 1} {why} in YAML 1.1 (it reads as "
                           f"{value}); write the number you mean, or quote it for text")


_BUILT_WITH_MAPPING = ("tag:yaml.org,2002:merge", "tag:yaml.org,2002:value")   # `<<` and `=` keys: no constructor
_PLAIN = {yaml.ScalarNode: "tag:yaml.org,2002:str", yaml.SequenceNode: "tag:yaml.org,2002:seq",
          yaml.MappingNode: "tag:yaml.org,2002:map"}


def _unknown_tags(node, out: list) -> None:
    """Messages for nodes whose tag no safe constructor reads (``!!python/object:os.system``,
    ``!foo``), each node retagged as the plain text, list or mapping it is, so the document can
    still be built and checked for its other problems (nothing of it is used: they are listed)."""
    known = _Loader.yaml_constructors
    for n in _nodes(node):
        if (n.tag not in known and n.tag not in _BUILT_WITH_MAPPING
                and not any(n.tag.startswith(p) for p in _Loader.yaml_multi_constructors)):
            out.append(f"the tag {n.tag.replace('tag:yaml.org,2002:', '!!')!r} at line {n.start_mark.line + 1} is "
                       "refused: configs take plain values only")
            n.tag = _PLAIN[type(n)]


def _key_value(k):
    """What a scalar key loads as, built on a throwaway constructor (a failure leaves no state
    in the document's own loader); a ``=`` key (the value tag) is the string ``=``, as the
    mapping's constructor makes it."""
    if k.tag == "tag:yaml.org,2002:value":
        return k.value
    return yaml.constructor.SafeConstructor().construct_object(k)


def load(text: str, numbers: list | None = None):
    """The document's data (safe types only); `yaml.YAMLError` for bombs, syntax errors and values
    their tag cannot read (``!!int abc``), and for duplicate keys in a mapping, plain numbers
    YAML 1.1 reads otherwise than they look and tags no safe constructor reads (``!!python/...``),
    unless ``numbers`` is a list: then one message each of those three is appended to it and the
    document is read as YAML 1.1 reads it (the last of duplicate keys wins, an unknown tag's node
    is plain text, list or mapping; the caller lists them with its own problems and uses
    nothing)."""
    _too_big(text)
    loader = _Loader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _expanded_size(node, {}, set())
        dup: list = []
        _duplicate_keys(node, dup, set(), _key_value)
        dup = [f"{d}: each key may appear once in a mapping" for d in dup]
        if dup and numbers is None:
            raise yaml.YAMLError("; ".join(dup))
        odd: list = dup
        if numbers is not None:
            _unknown_tags(node, odd)
        _yaml11_numbers(node, odd)
        if odd and numbers is not None:
            numbers += odd
        elif odd:
            raise yaml.YAMLError("; ".join(odd[:10]) + (f"; and {len(odd) - 10} more" if len(odd) > 10 else ""))
        try:
            return loader.construct_document(node)
        except (ValueError, KeyError, TypeError) as exc:     # e.g. `!!int abc`, `!!bool maybe`
            raise yaml.YAMLError(f"a value cannot be read as its tag says ({type(exc).__name__}: {exc})") from None
    except RecursionError:
        raise yaml.YAMLError("nested too deeply to read: refused") from None
    finally:
        loader.dispose()


def short(value, limit: int = 120) -> str:
    """``repr(value)`` cut to ``limit`` characters, for messages about user input."""
    try:
        r = reprlib_repr(value)
    except Exception:  # noqa: BLE001
        r = f"<{type(value).__name__}>"
    return r if len(r) <= limit else r[:limit - 3] + "..."


def reprlib_repr(value) -> str:
    import reprlib
    rp = reprlib.Repr()
    rp.maxlevel, rp.maxdict, rp.maxlist, rp.maxstring, rp.maxother = 3, 6, 6, 80, 80
    return rp.repr(value)
