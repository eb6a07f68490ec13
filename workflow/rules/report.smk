# The tables that carry the verdict, shown in the Snakemake report: the report offers a CSV
# only as a download, but shows an HTML page inline, so the claims table, the packing's cost
# and each calibration set's parameters and fit quality are also written as HTML (same
# caption as the CSV they render, which stays in the report for download).


def write_html_tables(inputs, outputs, log_path):
    """Render each CSV of ``inputs`` as the HTML table ``outputs[i]`` (pandas.DataFrame.to_html)."""
    import pandas as pd

    with open(log_path, "w") as log_file:
        for src, dst in zip(inputs, outputs):
            table = pd.read_csv(src)
            table.to_html(dst, index=False, na_rep="", float_format=lambda x: f"{x:.6g}", border=0)
            print(f"{src} -> {dst}: {len(table)} rows", file=log_file)


rule claims_table_html:
    input:
        f"{CLAIMS}/paper_claims.csv",
    output:
        report(f"{CLAIMS}/paper_claims.html", caption="../report/paper_claims.rst", category=CLAIMS_CATEGORY),
    resources:
        runtime=COST_SMALL.runtime,
        mem_mb=COST_SMALL.mem_mb,
    log:
        f"{RESULTS}/logs/report/claims_table_html.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/claims_table_html.tsv"
    run:
        write_html_tables(input, output, log[0])


rule packing_table_html:
    input:
        f"{RESULTS}/accuracy/packing_cost.csv",
    output:
        report(
            f"{RESULTS}/accuracy/packing_cost.html",
            caption="../report/packing_cost.rst",
            category="Accuracy and cost",
        ),
    resources:
        runtime=COST_SMALL.runtime,
        mem_mb=COST_SMALL.mem_mb,
    log:
        f"{RESULTS}/logs/report/packing_table_html.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/packing_table_html.tsv"
    run:
        write_html_tables(input, output, log[0])


REPORT_CALIBRATION_TABLES = ["params_table", "fit_quality"]


rule calibration_tables_html:
    input:
        [f"{RESULTS}/calibration/{{calset}}/{name}.csv" for name in REPORT_CALIBRATION_TABLES],
    output:
        [
            report(
                f"{RESULTS}/calibration/{{calset}}/{name}.html",
                caption=f"../report/{name}.rst",
                category="Calibration",
                subcategory="{calset}",
            )
            for name in REPORT_CALIBRATION_TABLES
        ],
    resources:
        runtime=COST_SMALL.runtime,
        mem_mb=COST_SMALL.mem_mb,
    log:
        f"{RESULTS}/logs/report/calibration_tables_html/{{calset}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/calibration_tables_html/{{calset}}.tsv"
    run:
        write_html_tables(input, output, log[0])


def report_table_targets():
    """The HTML tables of the report: claims, packing cost, each calibration set's parameters and fit."""
    return [
        *rules.claims_table_html.output,
        *rules.packing_table_html.output,
        *[f"{RESULTS}/calibration/{calset}/{name}.html" for calset in CALIBRATION_SETS for name in REPORT_CALIBRATION_TABLES],
    ]
