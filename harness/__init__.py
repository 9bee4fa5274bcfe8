"""mesh-shootout harness: config, datasets, noise, runner, metrics, results and reports."""
__version__ = "0.1.0"


def run(config_or_path, **overrides):
    """Run a config (path, YAML text or dict); return ``{task: pandas.DataFrame}``.

    ``overrides`` are the CLI options by name (``out``, ``workers``, ``executor``,
    ``scheduler``, ``resume``, ``timeout``, ``quiet``, ``export_benchmark_json``), refused where
    the CLI refuses them (see `harness.session.run`).
    """
    from .session import run as _run
    return _run(config_or_path, **overrides)


def evaluate(V, F, V_clean, F_clean, **kwargs):
    """The task's metrics of a result against a clean mesh (see `harness.scoring.evaluate`)."""
    from .scoring import evaluate as _evaluate
    return _evaluate(V, F, V_clean, F_clean, **kwargs)


def load_run(run_dir):
    """All rows of a run folder as one tidy DataFrame (every task's CSV; ``params`` expanded into one
    column per parameter, named as the parameter, or ``param_<name>`` where that name is taken)."""

    import pandas as pd

    from pathlib import Path

    from .errors import ShootoutError
    from .leaderboard import params_of
    from .results import RunFolder
    if not Path(run_dir).is_dir():
        raise ShootoutError(f"{run_dir}: no such run folder")
    folder = RunFolder(run_dir)
    why = folder.readable_problem()
    if why:
        raise ShootoutError(why)
    frames = folder.frames()
    if not frames:
        return pd.DataFrame()
    df = pd.concat(list(frames.values()), ignore_index=True, sort=False)
    params = [params_of(p) for p in df.get("params", [])]
    keys = sorted({k for p in params for k in p})
    cols = pd.DataFrame({(k if k not in df.columns else f"param_{k}"): [p.get(k) for p in params] for k in keys},
                        index=df.index)
    return pd.concat([df, cols], axis=1) if keys else df
