# What accuracy costs in time: the ODE work-precision study of the continuum
# model (always on: seconds) and the DEM resolution study (config accuracy.dem_study).


rule ode_work_precision:
    output:
        table=report(
            f"{RESULTS}/accuracy/ode_work_precision.csv",
            caption="../report/ode_work_precision.rst",
            category="Accuracy and cost",
        ),
        figure=report(
            f"{RESULTS}/accuracy/ode_work_precision.png",
            caption="../report/ode_work_precision.rst",
            category="Accuracy and cost",
        ),
    log:
        f"{RESULTS}/logs/accuracy/ode_work_precision.log",
    benchmark:
        f"{RESULTS}/benchmarks/accuracy/ode_work_precision.tsv"
    threads: 1
    shell:
        "{PY} -m model.work_precision --out {RESULTS}/accuracy > {log} 2>&1"


def accuracy_targets():
    targets = []
    if config.get("accuracy", {}).get("ode_work_precision", True):
        targets += rules.ode_work_precision.output
    return targets
