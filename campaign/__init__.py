"""The campaign: from the validated config to the DEM cases and their scene files.

Used by the Snakemake workflow (Snakefile, workflow/rules/), by dem_study and by the pre-flight check (preflight/):

- ``cases``: the table of DEM cases (pressure, inertial number, seed) and their labels;
- ``scenes``: the scene file of one case (the input of yade_scripts, docs/scene.md);
- ``scene_spec``: what the DEM scene accepts (defaults, ranges, protocol segments), read from yade_scripts/scene.py;
- ``summary``: the campaign's table, a row per case from its sidecars and pre-shear (``python -m campaign.summary``).
"""
