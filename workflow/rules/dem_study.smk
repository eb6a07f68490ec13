# The DEM resolution study (config accuracy.dem_study; dem_study/README.md).
# One factor at a time around accuracy.base (dem_study/grid.py): each point is a
# DEM case under {RESULTS}/accuracy/dem/<point>/, run by the DEM chain of dem.smk
# (rules dem_study_scene, _pack, _preshear, _heaviside), with the campaign's scene
# (campaign.scenes.scene_from_config) changed in one key.
#
# Cost of the default subset of config/config.yaml, estimated by the cost model
# (campaign/cost.py: documented throughput of YADE 2.3 M particle-steps/s at 500 disks,
# 0.8 M at 5,000, one thread; LAMMPS's 3.5 times that), steps per unit strain
# sqrt(4 kappa/pi)/(I dt_over_tc) over 1.9 strain, plus a pack of PACK_TIME time units: with the 3 repeated
# kappa = 1e5 seeds 19 DEM cases, about 1.4 core-hours (measured with the former,
# undamped packing, several times longer: 36 min + 13 min on 2 cores).
# `python -m dem_study estimate --configfile config/config.yaml [--subset full]`
# prints the estimate per point.
ACCURACY = config["accuracy"]  # the schema fills every default
DEM_STUDY = ACCURACY["dem_study"]
ACC_DEM = f"{RESULTS}/accuracy/dem"
DEM_POINTS = dem_grid.expand(ACCURACY) if DEM_STUDY else None
DEM_POINT_NAMES = list(dem_grid.unique_points(DEM_POINTS)["point"]) if DEM_STUDY else []


wildcard_constraints:
    point="base_s[0-9]+|[A-Za-z]+-[0-9.e-]+_s[0-9]+",


rule dem_study_points:
    output:
        f"{ACC_DEM}/points.csv",
    params:
        rows=DEM_POINTS.to_dict("records") if DEM_STUDY else [],  # reruns when the grid changes
    log:
        f"{RESULTS}/logs/accuracy/dem_study_points.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/dem_study_points.tsv"
    localrule: True
    run:
        DEM_POINTS.to_csv(output[0], index=False)
        with open(log[0], "w") as fh:
            print(f"{len(DEM_POINTS)} rows, {len(DEM_POINT_NAMES)} DEM cases", file=fh)


rule dem_study:
    input:
        points=rules.dem_study_points.output[0],
        runs=[
            f"{ACC_DEM}/{point}/{name}"
            for point in DEM_POINT_NAMES
            for name in ["pack.json", "preshear.json", "preshear.csv", "heaviside.json", "heaviside.csv"]
        ],
    output:
        table=report(
            f"{RESULTS}/accuracy/dem_cost.csv",
            caption="../report/dem_cost.rst",
            category="Accuracy and cost",
        ),
        figure=report(
            f"{RESULTS}/accuracy/dem_cost.png",
            caption="../report/dem_cost.rst",
            category="Accuracy and cost",
        ),
        transients=report(
            f"{RESULTS}/accuracy/dem_transients.png",
            caption="../report/dem_transients.rst",
            category="Accuracy and cost",
        ),
        mu_table=report(
            f"{RESULTS}/accuracy/mu_of_I.csv",
            caption="../report/mu_of_I.rst",
            category="Accuracy and cost",
        ),
        mu_figure=report(
            f"{RESULTS}/accuracy/mu_of_I.png",
            caption="../report/mu_of_I.rst",
            category="Accuracy and cost",
        ),
        repeats=report(
            f"{RESULTS}/accuracy/dem_repeats.csv",
            caption="../report/dem_repeats.rst",
            category="Accuracy and cost",
        ),
        summary=f"{RESULTS}/accuracy/dem_study.json",
    params:
        campaign_I=sorted({case["inertial_number"] for case in CASES.values()}),
        tolerance=[f"{k}={v}" for k, v in ACCURACY["tolerance"].items()],
        out=f"{RESULTS}/accuracy",
        steady_window=ACCURACY["steady_window"],
        heaviside_strain=ACCURACY["heaviside_strain"],
        transient_bin=ACCURACY["transient_bin"],
        quasi_static_tolerance=ACCURACY["quasi_static_tolerance"],
    resources:
        runtime=COST_DEM_STUDY_ANALYSIS.runtime,
        mem_mb=COST_DEM_STUDY_ANALYSIS.mem_mb,
    log:
        f"{RESULTS}/logs/accuracy/dem_study.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/dem_study.tsv"
    threads: 1
    shell:
        "{PY:q} -m dem_study analyse --points {input.points:q} --dem-dir {ACC_DEM:q} --out {params.out:q}"
        " --steady-window {params.steady_window:q} --heaviside-strain {params.heaviside_strain:q}"
        " --transient-bin {params.transient_bin:q} --campaign-I {params.campaign_I:q}"
        " --quasi-static-tolerance {params.quasi_static_tolerance:q}"
        " --tolerance {params.tolerance:q} > {log:q} 2>&1"
