"""The leaderboard's and the winners' tables as Markdown and LaTeX (booktabs): `to_markdown`,
`to_latex`, `winners_markdown`, `winners_latex`, with their captions (the Friedman p, the
Nemenyi critical difference where the Friedman test rejects at `ALPHA`, certified brackets,
standard errors, seeds) and the escaping of a cell's free text for each (`_md`, `_tex`).
"""
from __future__ import annotations

import pandas as pd

from .leaderboard_labels import noise_label, setting_text
from .leaderboard_validity import _installed_spec


LEFT_OUT = ("no measurement in some cells (the reference scored against itself): left out of the ranking, "
            "their other cells are in winners.md")


def _best(r) -> str:
    """The best variant, and those tied with it ("no valid result" where every result is invalid)."""
    if pd.isna(r.best) or not str(r.best):
        return "no valid result"
    tied = "" if pd.isna(r.tied_with_best) else str(r.tied_with_best)
    return f"{r.best} (tied: {tied})" if tied else str(r.best)


def _runner_up(r) -> str:
    """The runner-up, and those tied with it."""
    tied = "" if pd.isna(r.tied_with_runner_up) else str(r.tied_with_runner_up)
    return f"{r.runner_up} (tied: {tied})" if tied and str(r.runner_up) else ("" if pd.isna(r.runner_up) else str(r.runner_up))


def _g(x) -> str:
    return "" if x is None or pd.isna(x) else format(x, ".4g")


def _val(x, upper=None, se=None) -> str:
    """A winner's value as printed: ``[lower, upper]`` for a certified bracket whose ends differ
    at 4 digits, ``value ± se`` for a sampled metric, else the value (4 significant digits)."""
    text = _g(x)
    if text and upper is not None and not pd.isna(upper) and _g(upper) != text:
        return f"[{text}, {_g(upper)}]"
    if text and se is not None and not pd.isna(se):
        return f"{text} ± {format(se, '.2g')}"
    return text


SHARED_SE_NOTE = ("± its standard error over the sample every method of the cell shares (e.g. the sources: another "
                  "sample could move the values; the methods compare on this one, so ties ignore it), over seeds the "
                  "mean of theirs")


def _shared_se(specs: dict | None, task: str, metric: str) -> bool:
    """Whether ``metric`` of ``task`` declares an error over a shared sample (``se_shared``), by
    ``specs`` or else the installed task kind."""
    spec = (specs or {}).get(task)
    if spec is None:
        spec = _installed_spec(task)
    m = next((m for m in spec.get("metrics", []) if m.get("name") == metric), {})
    return m.get("se_shared") is True


def winners_markdown(w: pd.DataFrame, specs: dict | None = None) -> str:
    """winners.md from `winners`' frame; ``specs`` (the tasks' declarations) word the captions."""
    out = []
    for (task, metric), g in w.groupby(["task", "metric"], sort=False):
        inp = g["input_value"].notna().any()          # the input's own value, where the task measures it
        out.append(f"### {task}: best by {metric} ({g.iloc[0].better} is better)\n\n"
                   "| mesh | noise | setting | best | value | runner-up | value |" + (" input |" if inp else "") +
                   " invalid excluded |\n|---|---|---|---|---:|---|---:|" + ("---:|" if inp else "") + "---:|")
        out += [f"| {_md(r.mesh)} | {_md(noise_label(r.noise_model, r.noise_level))} | {_md(setting_text(r.setting))} | {_md(_best(r))} | "
                f"{_val(r.value, getattr(r, 'value_upper', None), getattr(r, 'value_se', None))} | "
                f"{_md(_runner_up(r))} | "
                f"{_val(r.runner_up_value, getattr(r, 'runner_up_upper', None), getattr(r, 'runner_up_se', None))} |"
                + (f" {_g(r.input_value)} |" if inp else "") + f" {r.invalid_excluded} |"
                for r in g.itertuples()]
        if _carries(g, "upper"):
            out.append(f"\n{metric}: the lower end of a certified bracket; [lower, upper] where the two differ "
                       "at 4 digits (means over seeds).")
        if _carries(g, "se"):
            out.append(f"\n{metric}: {SHARED_SE_NOTE}." if _shared_se(specs, task, metric) else
                       f"\n{metric}: a sampled estimate ± its standard error (of the mean over seeds).")
        if inp:
            out.append(f"\ninput: {metric} of the case's input itself; a result worse than it made the input worse.")
        out.append(_not_measured_note(g))
        out.append(_seeds_note(g))
        out.append("")
    return "\n".join(out)


def _not_measured_note(g: pd.DataFrame) -> str:
    """The variants left out of cells as no measurement there (`not_measured`), named, with in how
    many of the cells: neither among the variants nor the invalid ones."""
    if "not_measured" not in g:
        return ""
    names = [n for s in g["not_measured"] if isinstance(s, str) for n in s.split(", ") if n]   # blank: NaN from a CSV
    if not names:
        return ""
    counts = pd.Series(names).value_counts(sort=False)
    said = "; ".join(f"{k} ({v} of {len(g)} cells)" for k, v in counts.items())
    return f"\nLeft out as no measurement of the method (the task's rules: e.g. the reference scored against itself): {said}."


def _seeds_note(g: pd.DataFrame) -> str:
    """What the cells' winners rest on: how many noise draws (seeds), said plainly when one; a
    given noisy input (no seed to vary) said to be one fixed draw."""
    model = g["noise_model"].astype(str)
    given = " Given noisy inputs (a published pair) are one fixed draw each." if (model == "given").any() else ""
    noisy = g[(model != "none") & (model != "given")]
    if not len(noisy) or "seeds" not in noisy:
        return given and "\n" + given.strip()
    n = pd.to_numeric(noisy["seeds"], errors="coerce").dropna()
    if not len(n):
        return given and "\n" + given.strip()
    lo, hi = int(n.min()), int(n.max())
    said = f"{lo}" if lo == hi else f"{lo}-{hi}"
    one = (" A winner from one seed is one noise draw's: another draw may name another method (run more seeds, "
           "`noise: [{..., seeds: N}]`).") if lo == 1 else ""
    return f"\nNoisy cells rest on {said} noise seed(s) each.{one}{given}"


def _carries(g: pd.DataFrame, kind: str) -> bool:
    """Whether some winners row of ``g`` carries a bracket upper end (``kind`` ``upper``) or a
    standard error (``se``) for its value or its runner-up's (a caption then says so)."""
    cols = [c for c in (f"value_{kind}", f"runner_up_{kind}") if c in g]
    return bool(g[cols].notna().any(axis=None))


def _tex_val(r, which: str) -> str:
    """`_val` of a winners row's ``value`` or ``runner_up`` value, in LaTeX."""
    v = r.value if which == "value" else r.runner_up_value
    return _val(v, getattr(r, f"{which}_upper", None), getattr(r, f"{which}_se", None)).replace(" ± ", r" $\pm$ ")


def winners_latex(w: pd.DataFrame, specs: dict | None = None) -> str:
    """winners.tex from `winners`' frame; ``specs`` (the tasks' declarations) word the captions."""
    out = ["% mesh-shootout winners per cell; needs \\usepackage{booktabs} and \\usepackage{graphicx}"]
    for (task, metric), g in w.groupby(["task", "metric"], sort=False):
        inp = g["input_value"].notna().any()          # the input's own value, where the task measures it
        out += [r"\begin{table}[t]", r"\centering", FIT, r"\begin{tabular}{llllrlr" + ("r" if inp else "") + "}",
                r"\toprule", r"mesh & noise & setting & best & value & runner-up & value" + (" & input" if inp else "")
                + r" \\", r"\midrule"]
        out += [f"{_tex(r.mesh)} & {_tex(noise_label(r.noise_model, r.noise_level))} & {_tex(setting_text(r.setting))} & {_tex(_best(r))} & "
                f"{_tex_val(r, 'value')} & {_tex(_runner_up(r))} & {_tex_val(r, 'runner_up')}"
                + (f" & {_g(r.input_value)}" if inp else "") + " \\\\" for r in g.itertuples()]
        said = (f"; input: \\texttt{{{_tex(metric)}}} of the case's input itself (a result worse than it made the "
                "input worse)") if inp else ""
        if _carries(g, "upper"):
            said += "; values are the lower ends of certified brackets, [lower, upper] where the two differ at 4 digits"
        if _carries(g, "se"):
            said += (r"; values $\pm$ their standard errors over the sample every method of the cell shares "
                     r"(ties ignore them; over seeds the mean of theirs)" if _shared_se(specs, task, metric) else
                     r"; sampled estimates $\pm$ their standard errors")
        gone = _not_measured_note(g).strip()
        if gone:
            said += "; " + _tex(gone[0].lower() + gone[1:].rstrip("."))
        out += [r"\bottomrule", r"\end{tabular}}",
                f"\\caption{{{_tex(task)}: best valid method per cell by \\texttt{{{_tex(metric)}}} ({g.iloc[0].better} is "
                f"better); invalid results excluded{said}.}}", r"\end{table}", ""]
    return "\n".join(out)


ALPHA = 0.05                      # the level of the Friedman test and of the Nemenyi post-hoc test


def cd_applies(p, cd) -> bool:
    """Whether the Nemenyi critical difference may be read: the Friedman test rejected at `ALPHA`."""
    return not (p is None or pd.isna(p) or cd is None or pd.isna(cd)) and float(p) < ALPHA


def friedman_p_text(r0, num=lambda x, d: f"{x:.{d}g}", pm: str = "±") -> str:
    """``p = 0.043 ± 0.0014`` (the Friedman permutation p and its Monte Carlo standard error), or
    ``p < 0.00015`` when no permutation reached the observed statistic (3 / draws: the 95% upper
    bound of a rate never seen in that many draws); ``num(x, digits)`` formats a number."""
    p, se = float(r0.friedman_p), getattr(r0, "friedman_p_se", None)
    if se is None or pd.isna(se) or not se > 0:
        return f"p = {num(p, 2)}"
    draws = p * (1 - p) / se ** 2
    if p * (draws + 1) < 1.5:                  # no hit: p is 1 / (draws + 1)
        return f"p < {num(3.0 / draws, 2)}"
    return f"p = {num(p, 2)} {pm} {num(se, 1)}"


def _cd_text(r0, dash: str) -> str:
    if pd.isna(r0.critical_difference):
        return dash
    if pd.isna(r0.friedman_p):
        return "not applied (no Friedman test: one cell or one method)"
    if not cd_applies(r0.friedman_p, r0.critical_difference):
        return f"not applied (Friedman p >= {ALPHA:g}: no pair is shown to differ)"
    return f"{r0.critical_difference:.2f}"


def to_markdown(lb: pd.DataFrame) -> str:
    out = []
    for (task, metric), g in lb.groupby(["task", "metric"], sort=False):
        r0 = g.iloc[0]
        p = "p = —" if pd.isna(r0.friedman_p) else friedman_p_text(r0)
        cd = _cd_text(r0, "—")
        out.append(f"### {task}: {metric} ({r0.better} is better)\n\n{int(r0.cells)} cell{'' if int(r0.cells) == 1 else 's'}, Friedman {p}, "
                   f"Nemenyi critical difference (alpha 0.05) = {cd}\n\n| method | mean rank | missing | invalid |\n"
                   "|---|---:|---:|---:|")
        out += [f"| {_md(r.method)} | {_rank(r.mean_rank)} | {r.missing_cells} | {r.invalid_cells} |" for r in g.itertuples()]
        gone = getattr(r0, "left_out", "")
        if isinstance(gone, str) and gone:
            out.append(f"\nLeft out: {_md(gone)}: {LEFT_OUT}.")
        out.append("")
    return "\n".join(out)


def _md(s) -> str:
    """A table cell's text for Markdown: ``|`` escaped (it ends a cell), ``<`` ``>`` ``&`` as HTML
    entities (Markdown renderers pass raw HTML through; a mesh's file stem is free text), a line
    break as ``<br>`` (it ends the table row)."""
    t = str(s).replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace("|", "\\|")
    return t.replace("\r\n", "<br>").replace("\n", "<br>").replace("\r", "<br>")


def _rank(x: float) -> str:
    """A mean rank to 2 decimals, a half rounded up (2.125 is 2.13), as the report's
    ``toFixed(2)`` prints it (Python's format rounds a half to even: 2.12)."""
    from decimal import ROUND_HALF_UP, Decimal
    return str(Decimal(float(x)).quantize(Decimal("0.01"), rounding=ROUND_HALF_UP))


def _tex_num(x: float, digits: int = 2) -> str:
    """``x`` to ``digits`` significant digits for LaTeX math: ``1.5 \\times 10^{-5}``, not ``1.5e-05``."""
    t = f"{float(x):.{digits}g}"
    if "e" not in t:
        return t
    m, e = t.split("e")
    return f"{m} \\times 10^{{{int(e)}}}"


def _tex(s: str) -> str:
    """Text for a LaTeX table cell, in OT1 (pdflatex's default, which prints ``<`` ``>`` ``|``
    ``"`` as other glyphs) or T1: the special characters escaped, those four as text symbols,
    the characters of TeX's ligatures (``--`` an en dash, ``''`` a closing quote, ``!``` an
    inverted exclamation mark, T1's ``,,``) kept apart by empty groups, and a leading ``[`` or
    ``*`` behind ``{}`` (after ``\\\\`` or ``\\midrule`` it would be read as their argument).
    Characters outside LaTeX's UTF-8 tables (e.g. CJK) need xelatex or lualatex."""
    out = "".join({"_": r"\_", "&": r"\&", "%": r"\%", "#": r"\#", "$": r"\$", "{": r"\{", "}": r"\}",
                    "~": r"\textasciitilde{}", "^": r"\textasciicircum{}", "\\": r"\textbackslash{}",
                    "<": r"\textless{}", ">": r"\textgreater{}", "|": r"\textbar{}", '"': r"\texttt{\char34}",
                    "-": "-{}", "`": "{}`{}", "'": "'{}", ",": ",{}",   # no ligature: -- ``  '' !` ?` ,,
                    "\n": " ", "\r": " "}.get(c, c)           # a blank line would end the tabular's paragraph
                  for c in str(s))
    return "{}" + out if out[:1] in ("[", "*") else out


FIT = r"\resizebox{\ifdim\width>\linewidth\linewidth\else\width\fi}{!}{%"   # shrink a table wider than the text only


def to_latex(lb: pd.DataFrame) -> str:
    """booktabs tables, one per (task, metric)."""
    out = ["% mesh-shootout leaderboard; needs \\usepackage{booktabs} and \\usepackage{graphicx}"]
    for (task, metric), g in lb.groupby(["task", "metric"], sort=False):
        r0 = g.iloc[0]
        p = ("no Friedman test" if pd.isna(r0.friedman_p) else
             "Friedman $" + friedman_p_text(r0, lambda x, d: _tex_num(x, d), r"\pm") + "$ (permutation test)")
        gone = getattr(r0, "left_out", "")
        cd = _cd_text(r0, "--").replace(">=", r"$\geq$")
        out += [r"\begin{table}[t]", r"\centering", FIT, r"\begin{tabular}{lrrr}", r"\toprule",
                r"method & mean rank & missing & invalid \\", r"\midrule"]
        out += [f"{_tex(r.method)} & {_rank(r.mean_rank)} & {r.missing_cells} & {r.invalid_cells} \\\\"
                for r in g.itertuples()]
        out += [r"\bottomrule", r"\end{tabular}}",
                f"\\caption{{{_tex(task)}: mean rank by \\texttt{{{_tex(metric)}}} ({r0.better} is better) over "
                f"{int(r0.cells)} cell{'' if int(r0.cells) == 1 else 's'}; {p}, Nemenyi CD$_{{0.05}}$: {cd}."
                + (f" Left out: {_tex(gone)}: {_tex(LEFT_OUT)}." if isinstance(gone, str) and gone else "") + "}",
                r"\end{table}", ""]
    return "\n".join(out)
