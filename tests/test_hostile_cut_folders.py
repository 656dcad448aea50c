"""Corrupted cut folders: crafted damage and seeded mutations of cut.json and cut_embedding.npz.

Each folder is loaded with :func:`core.cut.io.load_cut` and every garment and
panel position is evaluated in a crash-counting worker under a capped address
space (:mod:`hostile_runner`): an out-of-range embedding index used to read
outside memory there. No case may crash or trace back, and every refusal is one
line naming the file (``cut.json`` or ``cut_embedding.npz``) and the key.
"""

import pytest
from conftest import sample
from hostile_cut_folders import case_list, make_case
from hostile_runner import run_checked, split_cases

CASES = case_list()
CRAFTED, MUTATED_CHUNKS = split_cases(CASES, 30)


def _run(cases, tmp_path):
    folders = [make_case(c, tmp_path) for c in cases]
    return run_checked(
        "hostile_cut_folders:check_cut",
        cases,
        folders,
        lambda folder: (f"{folder}/cut.json", f"{folder}/cut_embedding.npz"),
    )


def test_crafted_cut_folders_are_refused_naming_file_and_key(tmp_path):
    out = _run(CRAFTED, tmp_path)
    assert len(CRAFTED) > 50
    for (kind, name), (status, message) in out.items():
        assert status == ("ok" if kind == "valid" else "refused"), (kind, name, message)
    assert "'indices' has entries outside [0, 20)" in out[("npz", "index_out_of_range")][1]
    assert "'data' holds NaN" in out[("npz", "nan_weight")][1]
    assert "got a list" in out[("json", "top_level_list")][1]
    assert "panels[0].faces: expected rows of 3 indices" in out[("json", "faces_two_columns")][1]
    assert "not a zip file" in out[("npz", "empty_file")][1]
    assert "not UTF-8" in out[("encoding", "latin-1")][1]


@pytest.mark.parametrize("chunk", sample(MUTATED_CHUNKS, 3, seed=15), ids=lambda c: f"{c[0][0]}{c[0][1]}")
def test_mutated_cut_folders_never_crash(chunk, tmp_path):
    _run(list(chunk), tmp_path)


def test_a_saved_cut_reloads_unchanged(tmp_path):
    """The checks accept what save_cut writes, and the reloaded cut is the same."""
    import numpy as np
    from hostile_cut_folders import small_cut

    from core.cut.io import load_cut, save_cut

    cut = small_cut()
    save_cut(cut, tmp_path)
    back = load_cut(tmp_path)
    assert (back.embedding != cut.embedding).nnz == 0
    for a, b in zip(cut.panels, back.panels):
        np.testing.assert_array_equal(a.faces, b.faces)
        np.testing.assert_array_equal(a.ease, b.ease)
    np.testing.assert_array_equal(back.materials["extra_array"], cut.materials["extra_array"])
    assert back.hems.keys() == cut.hems.keys() and back.seams[0].verts_b.tolist() == [0, 1]
