"""Hostile and broken body-model files: crafted attacks and seeded mutations never crash or trace back.

Every case goes through every loading path a user reaches (``ease body
--model`` via :func:`core.cli.main`, and :func:`core.body.load_body`, which the
design, the cut and the add-on's *Add Body* use) in a worker process whose
address space is capped (:mod:`hostile_runner`): a segfault, a traceback or a
MemoryError is a failure, and so is a refusal that is not one line naming the
file. Crafted cases (raw-memory chumpy objects, dtype reference flags, memory
bombs, self-references, malformed arrays, NaN templates, broken zips and OBJs)
all run in CI; the seeded byte mutations of a valid pickle, npz and OBJ run as
a fixed sample (``--full``: all of them).
"""

import pickle

import numpy as np
import pytest
from conftest import sample
from hostile_models import case_list, make_case, small_model
from hostile_runner import run_checked, split_cases

CASES = case_list()
CRAFTED, MUTATED_CHUNKS = split_cases(CASES, 15)


def _run(cases, tmp_path):
    paths = [make_case(c, tmp_path) for c in cases]
    return run_checked("hostile_models:check_model", cases, paths, lambda path: (path,))


def test_crafted_model_files_are_refused_and_valid_ones_load(tmp_path):
    out = _run(CRAFTED, tmp_path)
    assert len(CRAFTED) > 150
    for (kind, name), (status, message) in out.items():
        if kind == "valid":
            assert status == "ok", (name, message)
        elif kind in ("pkl", "npz"):  # every crafted pickle and npz is an attack or broken
            assert status == "refused", (kind, name)
    by_name = {name.split("@")[0]: out[(kind, name)][1] for kind, name in out if kind == "pkl"}
    assert "refers to itself" in by_name["self_referencing_chumpy"]
    assert "over the limit" in by_name["setstate_huge"]
    assert "bytearray() of int" in by_name["bytearray_bomb"]
    assert "dtype flags" in by_name["dtype_object_flags"]
    assert "NaN or infinite" in out[("npz", "nan_v_template")][1]
    assert "not SMPL model .npz" in out[("npz", "npy_renamed")][1]
    assert "key 'v_template'" in out[("npz", "declares_1e12_elements")][1]
    assert "must be finite" in out[("obj", "nan_vertex")][1]
    assert "key 'weights': no vertex is skinned mostly to the" in out[("npz", "smpl_topology_one_joint")][1]


@pytest.mark.parametrize("chunk", sample(MUTATED_CHUNKS, 4, seed=15), ids=lambda c: f"{c[0][0]}{c[0][1]}")
def test_mutated_model_files_never_crash(chunk, tmp_path):
    _run(list(chunk), tmp_path)


def test_protocol_2_empty_array_loads():
    from core.body.unpickle import safe_load

    for protocol in range(6):
        got = safe_load(pickle.dumps({"a": np.zeros(0), "b": np.zeros((0, 3), np.float32)}, protocol=protocol))
        assert got["a"].shape == (0,) and got["b"].shape == (0, 3) and got["b"].dtype == np.float32


def test_limits_admit_a_real_smplx_file():
    """SMPL-X's largest arrays (shapedirs 10475x3x400, posedirs 10475x3x486 float64) fit under the limits."""
    from core.body.arrays import MAX_TOTAL_BYTES, check_shape

    sizes = [
        check_shape(s, 8, "smplx") * 8 for s in ((10475, 3), (10475, 3, 400), (10475, 3, 486), (55, 10475), (10475, 55))
    ]
    assert sum(sizes) < MAX_TOTAL_BYTES / 4
    with pytest.raises(Exception, match="over the limit"):
        check_shape((10**12,), 8, "bomb")


def test_pickle_and_npz_load_the_same_model(tmp_path):
    """The checked loaders change nothing for a valid file: pickle (protocols 0-5) == npz."""
    from core.body import load_body

    m = small_model()
    np.savez(tmp_path / "m.npz", **m)
    ref = load_body(str(tmp_path / "m.npz")).vertices({"beta1": 0.5})
    for protocol in range(6):
        p = tmp_path / f"m{protocol}.pickle"
        p.write_bytes(pickle.dumps(m, protocol=protocol))
        np.testing.assert_array_equal(load_body(str(p)).vertices({"beta1": 0.5}), ref)
