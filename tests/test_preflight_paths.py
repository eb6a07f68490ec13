"""Where results_dir and release may lie (preflight/paths.py), on working trees made for the test.

The config-level cases (a system folder, outside the tree with and without the opt-in, a
hidden folder, the home folder) are in tests/test_campaign_preflight.py; these need a tree
of their own: a results folder that is a link, a tree that itself lies in a hidden folder.
"""
from preflight.paths import release_problems, results_dir_problems


def test_a_results_folder_linked_to_a_system_folder_is_refused(tmp_path):
    (tmp_path / "results").symlink_to("/etc")
    (problem,) = results_dir_problems({"results_dir": "results"}, tmp_path, home=tmp_path / "home")
    assert "system folder /etc (through a link: /etc)" in problem


def test_a_working_tree_inside_a_hidden_folder_may_hold_its_results(tmp_path):
    root = tmp_path / ".cache" / "repo"
    root.mkdir(parents=True)
    assert results_dir_problems({"results_dir": str(root / "results")}, root, home=tmp_path) == []
    assert results_dir_problems({"results_dir": "results/.old"}, root, home=tmp_path) != []


def test_every_release_of_a_list_is_checked_and_named_by_its_index(tmp_path):
    config = {"release": ["data/a", "../b", "data/c"]}
    (problem,) = release_problems(config, tmp_path, home=tmp_path / "home")
    assert problem.startswith("config error: release[1] = '../b': lies outside the working tree")
    assert release_problems(dict(config, allow_outside_tree=True), tmp_path, home=tmp_path / "home") == []
