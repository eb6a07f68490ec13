"""The command line runs on its defaults, reads parameter files and rejects bad ones by name."""
import pandas as pd

from model import default_params, load_params, save_params
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
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(d, explicit_end=True))     # complete, as save_params ends it
    assert main(["simulate", "--params", str(tmp_path / "bad.yaml"), "--out", str(tmp_path)]) == 2
    assert "friction_eq2.k1" in capsys.readouterr().err


def calibrated_file(path):
    """A parameter file as the calibration writes it (``calibrate.tables.write_params``: the four blocks with
    full-precision values, then intervals and provenance)."""
    from calibrate.tables import write_params
    doc = default_params().to_dict()
    for block in ("friction_eq2", "friction_quadratic", "model1", "model2"):
        doc[block] = {k: v * 1.0123456789 for k, v in doc[block].items()}
    doc["intervals"] = {"model1": {"c1": [-260.0, -150.0], "X_c": [0.08, 0.09]}, "model2": {"c3": [20.0, 30.0]}}
    doc["provenance"] = {"source": "calibrate (python -m calibrate)", "date": "2026-11-27T00:00:00+00:00",
                         "command": "python -m calibrate --dem results/dem/p100000_I0.001_s1 --out results/calibration",
                         "cases": [f"results/dem/p100000_I0.001_s{s}" for s in (1, 2, 3)], "seeds": [1, 2, 3],
                         "default_route": {"model1": "curves", "model2": "curves"}, "synthetic_input": False}
    write_params(doc, path)
    return path


def test_simulate_refuses_a_parameter_file_cut_inside_its_last_value_naming_what_is_missing(tmp_path, capsys):
    """Issue 33: the calibration's file cut inside model2's c3 (``c3: -33.``; intervals and provenance gone)
    parsed and ran: every block and key is there, c3 reads as a shorter number. Here c3 = 25.308...: cut at 25."""
    whole = calibrated_file(tmp_path / "params.yaml").read_bytes()
    at = whole.index(b"c3: 25.") + len(b"c3: 25.")
    (tmp_path / "cut.yaml").write_bytes(whole[:at])
    assert main(["simulate", "--params", str(tmp_path / "cut.yaml"), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert f"{tmp_path / 'cut.yaml'}: cut short" in err and f"at byte {at} after line" in err and "'  c3: 25.'" in err
    assert "absent blocks: intervals, provenance" in err
    assert main(["simulate", "--params", str(tmp_path / "params.yaml"), "--out", str(tmp_path)]) == 0


def test_every_truncation_of_a_written_parameter_file_is_refused(tmp_path):
    """Cut at any byte (a copy or a write interrupted), the file is refused; whole, it reads."""
    whole = calibrated_file(tmp_path / "params.yaml").read_bytes()
    assert load_params(tmp_path / "params.yaml").provenance["seeds"] == [1, 2, 3]
    accepted = []
    for n in range(len(whole.rstrip(b"\n"))):
        (tmp_path / "cut.yaml").write_bytes(whole[:n])
        try:
            load_params(tmp_path / "cut.yaml")
            accepted.append(n)
        except ValueError:
            pass
    assert accepted == []
