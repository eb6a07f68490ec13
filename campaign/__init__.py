"""The campaign: from the validated config to the DEM cases and their scene files.

Used by the Snakemake workflow (Snakefile, workflow/rules/), by dem_study and by the pre-flight check (preflight/):

- ``cases``: the table of DEM cases (pressure, inertial number, seed) and their labels;
- ``scenes``: the scene file of one case (the input of yade_scripts, docs/scene.md);
- ``scene_spec``: what the DEM scene accepts (defaults, ranges, protocol segments), read from yade_scripts/scene.py;
- ``summary``: the campaign's table, a row per case from its sidecars and pre-shear (``python -m campaign.summary``);
- ``cost``: the one cost model of a DEM stage (its steps, disks and one-thread seconds), ``schedule``: the wall
  time of the DEM jobs on a number of cores;
- ``price``: a campaign's DEM priced before it runs (``python -m campaign estimate``, the pre-flight's price line);
- ``status``: a running or stopped campaign's progress, core-hours and ETA (``python -m campaign status``).
"""
