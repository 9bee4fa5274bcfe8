"""mesh-shootout harness: config, datasets, noise, runner, metrics, results and reports."""
__version__ = "0.1.0"


def run(config_or_path, **overrides):
    """Run a config (path, YAML text or dict); return ``{task: pandas.DataFrame}``.

    ``overrides`` are the CLI options by name (``out``, ``workers``, ``executor``,
    ``scheduler``, ``resume``, ``timeout``, ``quiet``).
    """
    from .session import run as _run
    return _run(config_or_path, **overrides)
