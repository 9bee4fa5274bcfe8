"""The HTML report of a run folder, built from its CSVs and run.json only."""
from .html import build_report

__all__ = ["build_report"]
