"""A plugin whose import is interrupted inside code run by a string ``exec``, where a Ctrl-C lands
when it arrives while a dataclass is being built (dataclasses compile their methods that way)."""
exec("raise KeyboardInterrupt")  # noqa: S102
