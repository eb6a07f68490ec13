"""The command line runs on its defaults, reads parameter files and rejects bad ones by name."""
import pandas as pd

from model import default_params, save_params
from model.cli import main


def test_simulate_runs_on_documented_defaults_and_says_so(tmp_path, capsys):
    assert main(["simulate", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "built-in defaults" in out and "X_c=0.0827" in out and "LSODA" in out
    tab = pd.read_csv(tmp_path / "heaviside.csv")
    assert set(tab.model) == {"model1", "model2"} and tab.notna().all().all()
    assert (tmp_path / "heaviside.png").stat().st_size > 10_000


def test_simulate_reads_a_parameter_file_and_a_table(tmp_path):
    save_params(default_params(), tmp_path / "p.yaml")
    pd.DataFrame({"t": [0, 1, 1.5, 3], "gammadot": [1, 1, -1, -1]}).to_csv(tmp_path / "h.csv", index=False)
    rc = main(["simulate", "--params", str(tmp_path / "p.yaml"), "--protocol", "table", "--table",
               str(tmp_path / "h.csv"), "--model", "model2", "--method", "RK4", "--out", str(tmp_path)])
    assert rc == 0 and len(pd.read_csv(tmp_path / "table.csv")) > 100


def test_bad_parameter_file_names_the_key_and_range(tmp_path, capsys):
    d = default_params().to_dict()
    d["friction_eq2"]["k1"] = -1.0
    import yaml
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(d))
    assert main(["simulate", "--params", str(tmp_path / "bad.yaml"), "--out", str(tmp_path)]) == 2
    assert "friction_eq2.k1" in capsys.readouterr().err
