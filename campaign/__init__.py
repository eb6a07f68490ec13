"""The campaign: from the validated config to the DEM cases and their scene files.

Used by the Snakemake workflow (Snakefile, workflow/rules/) and by dem_study:

- ``cases``: the table of DEM cases (pressure, inertial number, seed) and their labels;
- ``scenes``: the scene file of one case (the input of yade_scripts, docs/scene.md);
- ``preflight``: the checks the workflow runs on the config before any job.
"""
