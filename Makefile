# Set-up and entry points. Both `make quick` and `make test` install what they
# need (Debian's yade as root, the Python packages into .venv) and are idempotent.
SHELL := /bin/bash
VENV  := .venv
PY    := $(VENV)/bin/python
STAMP := $(VENV)/.installed
# Each entry point checks its preset first: the pre-flight names a missing or malformed config
# file with its line (Snakemake's own message has none), then every bad value, before any job.
PREFLIGHT := $(PY) -m preflight check

.PHONY: setup yade lammps venv quick paper bench test test-all slurm-test lint clean

# apt (YADE) and pip (.venv) are independent: on a fresh machine they download side by side.
setup:
	@$(MAKE) --no-print-directory -j2 yade venv

yade:
	@command -v yade >/dev/null || { \
	  if [ "$$(id -u)" = 0 ]; then apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq yade; \
	  else echo "YADE missing: run 'sudo apt-get install yade' (Debian package)"; exit 1; fi; }

# Debian's LAMMPS for the lammps engine (config `engine: lammps`) and its tests: `make test` and a
# preset that asks for it install it, a YADE preset does not wait for it. The package ships
# liblammps.so.0 only; lammps_scripts/lammpslib.py loads that name (no symbolic link needed).
LAMMPS_PY := /usr/bin/python3
lammps:
	@$(LAMMPS_PY) -c "import lammps" 2>/dev/null && command -v lmp >/dev/null || { \
	  if [ "$$(id -u)" = 0 ]; then apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq lammps python3-lammps; \
	  else echo "LAMMPS missing: run 'sudo apt-get install lammps python3-lammps' (Debian packages)"; exit 1; fi; }

# A preset's engine: LAMMPS installed first when the config file says `engine: lammps`.
ENGINE_OF = if grep -Eq '^engine:[[:space:]]*lammps' $(1); then $(MAKE) --no-print-directory lammps; fi

venv: $(STAMP)
$(STAMP): requirements.txt
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -r requirements.txt
	touch $(STAMP)

# The quick campaign: every figure and table of the study in results/ (its time: README, "The presets and what each costs").
quick: setup
	@$(call ENGINE_OF,config/quick.yaml)
	$(PREFLIGHT) config/quick.yaml
	$(VENV)/bin/snakemake -j2 --configfile config/quick.yaml
	$(VENV)/bin/snakemake --configfile config/quick.yaml --report results/report.html

# The paper's campaign (hours on 2 cores).
paper: setup
	@$(call ENGINE_OF,config/config.yaml)
	$(PREFLIGHT) config/config.yaml
	$(VENV)/bin/snakemake -j2
	$(VENV)/bin/snakemake --report results/report.html

# Benchmarks of the code's own speed, in no preset's study: the batched integrator against a
# loop of model.simulate (about a minute) and every calibration set of the quick campaign with
# the per-run and the batched integrator (about 11 minutes of one core), the DEM stage
# against bare YADE (4 paired runs of a 338-disk pre-shear, about 5 minutes of one core), and
# LAMMPS's stage against YADE's (tools/engine_benchmark.py: paired pre-shears at 626 and about
# 5,000 disks, bare LAMMPS on 1 and 2 MPI ranks; its packings dominate, about 15 minutes); the
# quick campaign's DEM and calibration run first where results/ lacks them.
BENCH := results/accuracy/batched_cost.csv results/accuracy/calibration_cost.csv results/accuracy/stage_overhead.csv results/accuracy/engine_throughput.csv
bench: setup lammps
	$(PREFLIGHT) config/quick.yaml
	$(VENV)/bin/snakemake -j2 $(BENCH) --configfile config/quick.yaml

# The suite on both cores (pytest-xdist, one test file per worker so that a module's fixture
# runs once), then the tests marked serial (a Slurm daemon, signal timing) alone. The tests
# marked heavy (end-to-end tiny studies and releases, coverage studies) run in test-all.
# On one core, without xdist: $(PY) -m pytest -q -p no:xdist
test: setup lammps
	$(PREFLIGHT) config/ci.yaml
	$(VENV)/bin/lint-imports --no-cache
	$(PY) -m pytest -q -n 2 --dist loadfile -m "not serial and not heavy"
	$(PY) -m pytest -q -p no:xdist -m "serial and not heavy"

test-all: test
	$(PY) -m pytest -q -n 2 --dist loadfile -m "heavy"

# The CI preset through profiles/slurm on a one-node Slurm started here (root;
# workflow/scripts/slurm_local.sh up/down; about 10 minutes).
slurm-test: setup
	RUN_SLURM=1 $(PY) -m pytest -q -s -m slurm tests/test_slurm_profile.py

clean:
	rm -rf results logs benchmarks .snakemake
