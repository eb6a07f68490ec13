"""Every reversal of every protocol by its kind: a schedule's step joins the Heaviside runs, its half cosine
the sinusoidal ones, and a reversal back along the pre-shear (+1) is mirrored into the frame of the -1 ones.

Model-made cases (dem_contract.synthetic) with schedules; no YADE.
"""
import numpy as np
import pandas as pd
import pytest

from compare import comparison, figures
from compare.dem import canonical, load_reversals
from dem_contract import DEMInputError, fabric_angle_deg, fabric_norm, synthetic
from dem_contract.derived import mirror_reversal, reversal_kinds
from model import default_params, save_params

ALTERNATE = [(0.3, -1), (0.4, 1, 0.2)]   # the bulk preset's schedule: a step against, a half cosine back


# --- the kind of each reversal -----------------------------------------------------------------

def test_a_reversals_kind_and_direction_come_from_the_sidecar_its_segments_or_the_classic_name():
    side = {"reversals": [{"t": 1.0, "strain": 1.0, "direction": -1, "transition": "heaviside"},
                          {"t": 2.0, "strain": 0.7, "direction": 1, "transition": "half_cosine",
                           "transition_strain": 0.2}]}
    assert reversal_kinds(side, "alternate") == [
        {"kind": "heaviside", "direction": -1, "transition_strain": None},
        {"kind": "sinusoidal", "direction": 1, "transition_strain": 0.2}]
    # the expanded segments say the same: a segment in the pre-shear's direction first is no reversal
    segs = {"segments": [{"strain": 0.1, "direction": 1, "transition": "heaviside"},
                         {"strain": 0.3, "direction": -1, "transition": "heaviside"},
                         {"strain": 0.2, "direction": -1, "transition": "heaviside"},
                         {"strain": 0.4, "direction": 1, "transition": "half_cosine", "transition_strain": 0.2}]}
    assert reversal_kinds(segs, "alternate") == reversal_kinds(side, "alternate")
    assert reversal_kinds({}, "heaviside") == [{"kind": "heaviside", "direction": -1, "transition_strain": None}]
    assert reversal_kinds({"scene": {"sinusoidal": {"transition_strain": 0.1}}}, "sinusoidal") == [
        {"kind": "sinusoidal", "direction": -1, "transition_strain": 0.1}]


def test_a_schedule_whose_sidecar_does_not_say_its_reversals_is_named_as_unknown():
    with pytest.raises(DEMInputError, match="alternate.csv: .*kind of the reversals of schedule 'alternate' is unknown"):
        reversal_kinds({"reversal_t": 3.0}, "alternate", what="alternate.csv")
    with pytest.raises(DEMInputError, match="reversal 1: transition 'ramp' is not one of heaviside, half_cosine"):
        reversal_kinds({"reversals": [{"direction": -1, "transition": "ramp"}]}, "alternate")


# --- compare: grouping by kind ------------------------------------------------------------------

@pytest.fixture(scope="module")
def alternate(tmp_path_factory):
    """Two model-made seeds with heaviside, sinusoidal and the schedule `alternate`, compared at the truth."""
    root = tmp_path_factory.mktemp("alt")
    params = default_params()
    save_params(params, root / "params.yaml")
    dirs = synthetic.write_ensemble(root / "dem", params, seeds=(1, 2), preshear_strain=1.5, reversal_strain=0.4,
                                    transition_strain=0.2, schedules={"alternate": ALTERNATE})
    return root, dirs, comparison.run(dirs, root / "params.yaml", ["heaviside", "sinusoidal", "alternate"])


def test_a_schedules_half_cosine_reversal_is_grouped_with_the_sinusoidal_runs_and_its_step_with_the_heaviside(
        alternate, tmp_path):
    root, dirs, c = alternate
    seeds = c.errors[c.errors["level"] == "seed"]
    tags = seeds.drop_duplicates("protocol").set_index("protocol")[["kind", "reversal", "direction"]]
    assert tags.to_dict("index") == {
        "heaviside": {"kind": "heaviside", "reversal": 1, "direction": -1},
        "sinusoidal": {"kind": "sinusoidal", "reversal": 1, "direction": -1},
        "alternate_r1": {"kind": "heaviside", "reversal": 1, "direction": -1},
        "alternate_r2": {"kind": "sinusoidal", "reversal": 2, "direction": 1}}
    # the imposed history follows the kind, not the protocol's name: a step is one constant rate (0),
    # a half cosine the measured rate (1: not smoothed)
    smoothing = seeds.groupby("protocol")["rate_smoothing"].unique().to_dict()
    assert [list(smoothing[p]) for p in ("heaviside", "alternate_r1", "sinusoidal", "alternate_r2")] == [
        [0], [0], [1], [1]]
    assert seeds["status"].eq("ok").all()
    # each figure holds every ensemble of its kind
    drawn = {k: sorted(p for _, p in figures.reversal_figure(c.ensembles, k, tmp_path / f"{k}.png"))
             for k in ("heaviside", "sinusoidal")}
    assert drawn == {"heaviside": ["alternate_r1", "heaviside"], "sinusoidal": ["alternate_r2", "sinusoidal"]}
    assert (tmp_path / "sinusoidal.png").stat().st_size > 10_000
    # the classic rows keep their columns, the tags come last
    assert list(c.errors.columns[-3:]) == ["kind", "reversal", "direction"]
    assert list(c.errors.columns[:6]) == ["set", "level", "case", "group", "protocol", "in_sample"]


def test_a_schedule_whose_sidecar_direction_disagrees_with_its_rate_is_refused(alternate, tmp_path):
    import json
    import shutil
    root, dirs, c = alternate
    case = tmp_path / dirs[0].name
    shutil.copytree(dirs[0], case)
    meta = json.loads((case / "alternate.json").read_text())
    meta["reversals"][1]["direction"] = -1
    meta["reversals"][0]["direction"] = 1
    (case / "alternate.json").write_text(json.dumps(meta))
    with pytest.raises(DEMInputError, match="alternate.csv: reversal 1 shears with sign -1, its sidecar's direction"):
        load_reversals(case, "alternate")


# --- mirroring a +1 reversal ------------------------------------------------------------------

@pytest.fixture(scope="module")
def back_and_forth(tmp_path_factory):
    """A Heaviside reversal from the steady state, and a schedule that reaches the reversed steady state
    (3 strain against the pre-shear) before it reverses back (+1) for as long."""
    case = synthetic.write_case(tmp_path_factory.mktemp("back") / "p1_I0.001_s1", default_params(), seed=1,
                                preshear_strain=1.5, reversal_strain=0.4, protocols=("heaviside",),
                                schedules={"back": [(3.0, -1), (0.4, 1)]})
    (h,) = load_reversals(case, "heaviside")
    _, back = load_reversals(case, "back")
    return h, back


def on_grid(rev, data, s):
    return {c: np.interp(s, rev.data["s_rev"].to_numpy(), data[c].to_numpy()) for c in ("A_xx", "A_xy", "mu")}


def test_a_mirrored_plus_one_reversal_of_model_made_data_equals_the_minus_one_reversal(back_and_forth):
    h, back = back_and_forth
    assert (h.direction, back.direction, back.kind) == (-1, 1, "heaviside")
    s = h.data["s_rev"].to_numpy()
    s = s[s <= back.data["s_rev"].iloc[-1]]
    minus, plus = on_grid(h, h.data, s), on_grid(back, canonical(back), s)
    raw = on_grid(back, back.data, s)
    # in its own frame the return reversal is the -1 one reflected: A_xy of the other sign
    assert np.max(np.abs(raw["A_xy"] + minus["A_xy"])) < 2e-3
    assert np.max(np.abs(raw["A_xy"] - minus["A_xy"])) > 0.02
    # mirrored, it is the -1 reversal: fabric components, |A|, theta_A and mu
    for q in ("A_xx", "A_xy", "mu"):
        assert np.max(np.abs(plus[q] - minus[q])) < 2e-3, q
    th_plus = fabric_angle_deg(plus["A_xx"], plus["A_xy"])
    th_minus = fabric_angle_deg(minus["A_xx"], minus["A_xy"])
    assert np.max(np.abs((th_plus - th_minus + 90) % 180 - 90)) < 1.0
    assert np.max(np.abs(fabric_norm(plus["A_xx"], plus["A_xy"]) - fabric_norm(minus["A_xx"], minus["A_xy"]))) < 2e-3
    # the reflection's own theta_A column is the reflected angle, and twice is the identity
    m = canonical(back)
    assert np.allclose(m["theta_A"], np.mod(180.0 - back.data["theta_A"], 180.0))
    pd.testing.assert_frame_equal(mirror_reversal(m), back.data, rtol=0, atol=1e-9)
    assert canonical(h) is h.data   # a -1 reversal is left as it is


def test_a_plus_one_reversal_is_compared_in_the_frame_of_the_minus_one_ones(back_and_forth, tmp_path):
    h, back = back_and_forth
    save_params(default_params(), tmp_path / "params.yaml")
    c = comparison.run([h.path.parent], tmp_path / "params.yaml", ["heaviside", "back"])
    pred = c.predictions[c.predictions["source"] == "model1"]
    first = {p: g.iloc[0] for p, g in pred.groupby("protocol")}
    # both reversals start from (nearly) the same canonical fabric: A_xy > 0 before a -1 reversal
    assert first["back_r2"]["A_xy"] == pytest.approx(first["heaviside"]["A_xy"], abs=2e-3)
    assert first["back_r2"]["theta_A"] == pytest.approx(first["heaviside"]["theta_A"], abs=1.0)
    # and the errors are those of the run in its own frame (a reflection changes no error)
    e = c.errors[(c.errors["level"] == "seed") & (c.errors["model"] == "model1")].set_index("protocol")
    assert e.loc["back_r2", "rmse_A_norm"] < 1e-3 and e.loc["back_r2", "direction"] == 1
