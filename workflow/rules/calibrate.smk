# Calibration: DEM time series -> alpha1, alpha2 vs X -> fits of Eq. 6, Eq. 2, Model 2.
# One calibration per "set" of config["calibration"]["sets"]: which cases and
# protocols it learns from (the held-out comparisons use the others).


def calibration_sets():
    """Calibration sets: name -> dict(cases=[labels], protocols=[...]).

    A set may restrict protocols and pick pressures / inertial numbers; "all"
    (or a missing key) keeps every value of the campaign. The set "all" always
    exists: every case and every protocol; so do one set per pressure and one
    per inertial number when the campaign has several.
    """
    sets = {"all": {}}
    # With several loadings, one set per pressure and per inertial number: the
    # held-out comparison calibrates on one and predicts the others.
    pressures = sorted({case["pressure"] for case in CASES.values()})
    rates = sorted({case["inertial_number"] for case in CASES.values()})
    if len(pressures) > 1:
        sets.update({f"p{_fmt(p)}": {"pressures": [p]} for p in pressures})
    if len(rates) > 1:
        sets.update({f"I{_fmt(I)}": {"inertial_numbers": [I]} for I in rates})
    sets.update(config.get("calibration", {}).get("sets", {}))
    out = {}
    for name, spec in sets.items():
        protocols = [p for p in spec.get("protocols", PROTOCOLS) if p in PROTOCOLS]
        labels = [
            label
            for label, case in CASES.items()
            if spec.get("pressures", "all") == "all" or case["pressure"] in spec["pressures"]
            if spec.get("inertial_numbers", "all") == "all"
            or any(abs(case["inertial_number"] / I - 1) < 1e-6 for I in spec["inertial_numbers"])
        ]
        if labels and protocols:
            out[name] = dict(cases=labels, protocols=protocols)
    return out


CALIBRATION_SETS = calibration_sets()
CALIBRATION_FIGURES = [
    "fig2a_stress_vs_Axy",
    "fig2b_mu_vs_X",
    "fig3a_alpha1_vs_X",
    "fig3b_alpha2_vs_X",
]
CALIBRATION_TABLES = ["params_table", "backsolve_alpha_vs_X", "fit_quality"]


def calibration_params(calset):
    return f"{RESULTS}/calibration/{calset}/params.yaml"


rule calibrate:
    input:
        series=lambda wc: [
            f"{case_dir(label)}/{stage}.csv"
            for label in CALIBRATION_SETS[wc.calset]["cases"]
            for stage in ["preshear", *CALIBRATION_SETS[wc.calset]["protocols"]]
        ],
    output:
        params=f"{RESULTS}/calibration/{{calset}}/params.yaml",
        tables=[
            report(
                f"{RESULTS}/calibration/{{calset}}/{name}.csv",
                caption=f"../report/{name}.rst",
                category="Calibration",
                subcategory="{calset}",
            )
            for name in CALIBRATION_TABLES
        ],
        figures=[
            report(
                f"{RESULTS}/calibration/{{calset}}/{name}.png",
                caption=f"../report/{name}.rst",
                category="Calibration",
                subcategory="{calset}",
            )
            for name in CALIBRATION_FIGURES
        ],
    params:
        dirs=lambda wc: [case_dir(label) for label in CALIBRATION_SETS[wc.calset]["cases"]],
        protocols=lambda wc: CALIBRATION_SETS[wc.calset]["protocols"],
        options=config.get("calibration", {}).get("options", ""),
        out=lambda wc: f"{RESULTS}/calibration/{wc.calset}",
    log:
        f"{RESULTS}/logs/calibration/{{calset}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/calibration/{{calset}}.tsv"
    threads: 1
    shell:
        "{PY} -m calibrate --dem {params.dirs} --protocols {params.protocols}"
        " --out {params.out} {params.options} > {log} 2>&1"


def calibration_targets():
    return [calibration_params(name) for name in CALIBRATION_SETS]
