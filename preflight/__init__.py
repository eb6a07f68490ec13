"""The pre-flight check: every bad config is named before any job runs (``checks``).

It sits above the stages it validates: it asks calibrate's and compare's own
argument parsers about their options, dem_study for its grid, and the DEM's
scene validator (through ``campaign.scene_spec``) about every scene. No stage
imports it; the Snakefile calls ``check`` and ``stop_on_problems``, and
``python -m preflight check CONFIGFILE...`` runs it alone.
"""
from campaign.configfile import ConfigProblem, load_configfile

from .checks import check, stop_on_problems

__all__ = ["ConfigProblem", "check", "load_configfile", "stop_on_problems"]
