"""A DEM stage across Slurm time limits: checkpoint on SIGTERM, retry, resume.

Runs one pre-shear of the CI cell, lengthened to ``--strain`` (default 30, about
4.5 minutes on one core), through ``profiles/slurm`` with a time limit of
``attempt`` minutes (1, 2, 3, ...), so Slurm stops it at its limit (SIGTERM,
then SIGKILL after KillWait), the stage writes its checkpoint and exits 4, and
Snakemake's retry resubmits it with a longer limit; the stage resumes from the
checkpoint. Then it checks the series: t and strain strictly increasing, and
every row on the stage's sample grid (the step spacing of the coarse part is
one constant), so no gap and no duplicated row.

    workflow/scripts/slurm_local.sh up
    .venv/bin/python workflow/scripts/slurm_timelimit_demo.py --out /tmp/demo
    workflow/scripts/slurm_local.sh down

Prints allocations used (Slurm job ids and their end states), rows and gaps;
exit code 1 if the series has a gap or a duplicated row.
"""
import argparse
import json
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

ROOT = Path(__file__).resolve().parents[2]
CASE = "p100000_I0.01_s1"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True, help="results dir (created)")
    ap.add_argument("--strain", type=float, default=30.0, help="pre-shear strain (default 30)")
    ap.add_argument("--retries", type=int, default=4)
    args = ap.parse_args(argv)

    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    config = yaml.safe_load((ROOT / "config/ci.yaml").read_text())
    config["seeds"] = [1]
    config["preshear"]["strain"] = args.strain
    config["results_dir"] = str(out / "results")
    (out / "demo.yaml").write_text(yaml.safe_dump(config))
    logs = out / "slurm_logs"
    target = f"{out}/results/dem/{CASE}/preshear.csv"
    cmd = [sys.executable, "-m", "snakemake", "--profile", "profiles/slurm",
           "--configfile", str(out / "demo.yaml"), "--retries", str(args.retries),
           "--set-resources", "dem_preshear:runtime=attempt",  # minutes: 1, 2, 3, ...
           "--slurm-logdir", str(logs), "--slurm-keep-successful-logs",
           "--slurm-init-seconds-before-status-checks", "10", target]
    t0 = time.monotonic()
    with open(out / "snakemake.log", "w") as fh:
        run = subprocess.run(cmd, cwd=ROOT, stdout=fh, stderr=subprocess.STDOUT)
    wall = time.monotonic() - t0
    print(f"snakemake exit {run.returncode} after {wall:.0f} s (log {out / 'snakemake.log'})")

    text = (out / "snakemake.log").read_text()
    jobs = sorted({int(j) for j in re.findall(r"SLURM jobid (\d+)", text)})
    preshear_logs = sorted(logs.glob("rule_dem_preshear/**/*.log"))
    print(f"pre-shear allocations (Slurm logs): {len(preshear_logs)}")
    for log in preshear_logs:
        tail = [ln for ln in log.read_text().splitlines() if "CANCELLED" in ln or "DUE TO TIME LIMIT" in ln]
        print(f"  {log.name}: {'stopped at its time limit' if tail else 'ran to the end'}")
    if run.returncode != 0:
        return 1

    series = pd.read_csv(target)
    side = json.loads(Path(target.replace(".csv", ".json")).read_text())
    t, strain = series["t"].to_numpy(), series["strain"].to_numpy()
    dt_rows = np.diff(t)
    coarse = dt_rows[len(dt_rows) // 2:-1]  # past the fine window, before the end row: one fixed step count apart
    duplicated = int((dt_rows <= 0).sum())
    gaps = int((coarse > 1.5 * np.median(coarse)).sum()) + int((np.diff(strain) <= 0).sum())
    spread = (coarse.max() - coarse.min()) / np.median(coarse)
    print(f"rows {len(series)}, strain {strain[0]:.4f} .. {strain[-1]:.4f}, "
          f"coarse row spacing in t: relative spread {spread:.1e}, duplicated rows {duplicated}, gaps {gaps}")
    print(f"sidecar: samples {side.get('samples')}; Slurm jobs of this run {jobs}")
    return 0 if duplicated == 0 and gaps == 0 and spread < 1e-6 else 1


if __name__ == "__main__":
    sys.exit(main())
