"""The blow-up guards both engines share (yade_scripts/rows.py, pure Python and numpy): a NaN or a
disk outside the walls is named with the sample; a sound sample passes."""
import math

import numpy as np

from campaign.scene_spec import yade_scripts_module

rows = yade_scripts_module("rows")
WALLS = dict(fx_top=1.0, fy_top=-2.0, y_bot=0.0, y_top=10.0)
ROW = dict(t=1.5, strain=0.1, sigma_xy=0.3, p=1.0, gap=10.0)


def test_a_sound_sample_passes_the_state_guard():
    assert rows.state_problem(ROW, WALLS, np.array([1.0, 5.0, 9.0]), 1.0, "step 7") is None


def test_a_nan_in_the_row_or_the_positions_is_named_with_its_sample():
    for row, ys in ((dict(ROW, sigma_xy=math.nan), np.array([1.0])), (ROW, np.array([1.0, math.nan]))):
        assert rows.state_problem(row, WALLS, ys, 1.0, "iteration 12") == \
            "NaN in positions or forces at iteration 12 (t = 1.5000)"


def test_a_disk_outside_the_walls_is_named_with_its_height_in_d():
    why = rows.state_problem(ROW, WALLS, np.array([1.0, 12.0, -1.0]), 2.0, "step 3")
    assert why == "disk 1 left the cell at step 3 (y = 6.000 d, walls at 0.000 d and 5.000 d)"
