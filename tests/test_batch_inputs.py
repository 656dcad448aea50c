"""core.batch inputs without a cluster: body tables, samples, betas, item ids, the manifest journal,
the GarmentCode placement."""

from __future__ import annotations

import json

import numpy as np
import pytest

from core.batch import BodySourceError, Options, make_items, read_betas, read_measurements, sample_anny
from core.batch.garmentcode import placement
from core.batch.manifest import Journal, compact, comparable, completed, read_rows
from core.errors import EaseError

ANNY_PARAMS = {k: (0.0, 1.0, 0.5) for k in ("age", "gender", "height", "muscle", "proportions", "weight")}


def _csv(tmp_path, text, name="bodies.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_measurement_table(tmp_path):
    p = _csv(tmp_path, "name,height,bust,waist,hip,size\nann,170,92,74,98,\n,,,,,l\nhip only,,,,101,\n")
    bodies = read_measurements(p)
    assert [b.kind for b in bodies] == ["measurements", "size", "measurements"]
    assert bodies[0].label == "ann" and bodies[0].value == {"height": 170, "chest": 92, "waist": 74, "hip": 98}
    assert bodies[1].value == "L" and bodies[1].label == "row 2"
    assert bodies[2].value == {"hip": 101.0} and bodies[2].origin == "bodies.csv row 3"


def test_sizes_of_a_chart(tmp_path):
    """A ``chart`` column or a qualified size names a size of another chart; a bare size stays
    bare (the design's own chart reads it, as ``ease transfer`` does)."""
    p = _csv(tmp_path, "size,chart\nm,women\nmen:L,\nS,\n")
    assert [b.value for b in read_measurements(p)] == ["women:M", "men:L", "S"]


@pytest.mark.parametrize(
    "text, words",
    [
        ("height,waist\n170,80\n180,eighty\n", ["bodies.csv", "row 2", "'waist'", "'eighty'"]),
        ("height,knee\n170,80\n", ["bodies.csv", "column 2", "'knee'"]),
        ("height,size\n170,XXL\n", ["row 1", "'size'", "XXL"]),
        ("height,size\n170,M\n", ["row 1", "not both"]),
        ("size,chart\n5XL,women\n", ["row 1", "'size/chart'", "S, M, L"]),
        ("size,chart\nM,kids\n", ["row 1", "kids"]),
        ("height,chart\n170,women\n", ["row 1", "'chart'", "no size"]),
        ("height,waist\n170,80,3\n", ["row 1", "3 cells"]),
        ("height,waist\n,\n", ["bodies.csv", "no body rows"]),
        ("", ["empty"]),
        ("height,chest,bust\n1,2,3\n", ["both 'chest' and 'bust'"]),
    ],
)
def test_bad_tables_name_file_row_and_column(tmp_path, text, words):
    with pytest.raises(BodySourceError) as exc:
        read_measurements(_csv(tmp_path, text))
    msg = str(exc.value)
    assert "\n" not in msg and isinstance(exc.value, EaseError)
    for w in words:
        assert w in msg, msg


def test_missing_table_is_one_line(tmp_path):
    with pytest.raises(BodySourceError, match="cannot read"):
        read_measurements(tmp_path / "nope.csv")


def test_sample_is_seeded_per_body_and_in_range():
    a = sample_anny(5, seed=3, parameters=ANNY_PARAMS)
    b = sample_anny(8, seed=3, parameters=ANNY_PARAMS)
    assert [x.value for x in a] == [x.value for x in b[:5]]  # body i does not depend on N
    assert a[0].value != sample_anny(1, seed=4, parameters=ANNY_PARAMS)[0].value
    for body in b:
        assert set(body.value) == set(ANNY_PARAMS)
        assert all(0.0 <= v <= 1.0 for v in body.value.values())
        assert 2 / 3 <= body.value["age"] <= 1.0  # adults
    with pytest.raises(BodySourceError, match="--sample"):
        sample_anny(0, parameters=ANNY_PARAMS)
    with pytest.raises(BodySourceError, match="--seed"):
        sample_anny(2, seed=-1, parameters=ANNY_PARAMS)


def _smpl_params(tmp_path):
    from smpl_synth import tube_model

    from core.body import load_body

    path = tmp_path / "tube.npz"
    np.savez(path, **tube_model(n_betas=3))
    return load_body(str(path)).shape_parameters()


def test_betas_files(tmp_path):
    params = _smpl_params(tmp_path)
    betas = np.array([[0.5, -1.0, 0.0], [1.0, 2.0, -0.5]])
    np.save(tmp_path / "b.npy", betas)
    np.savez(tmp_path / "b.npz", betas=betas[:, :2])
    (tmp_path / "b.csv").write_text("beta0,beta1,beta2\n0.5,-1,0\n1,2,-0.5\n")
    for name in ("b.npy", "b.csv"):
        bodies = read_betas(tmp_path / name, params)
        assert [b.value for b in bodies] == [
            {"beta0": 0.5, "beta1": -1.0, "beta2": 0.0},
            {"beta0": 1.0, "beta1": 2.0, "beta2": -0.5},
        ]
    assert read_betas(tmp_path / "b.npz", params)[1].value == {"beta0": 1.0, "beta1": 2.0}


def test_bad_betas_name_file_row_and_column(tmp_path):
    params = _smpl_params(tmp_path)
    np.save(tmp_path / "wide.npy", np.zeros((2, 5)))
    np.save(tmp_path / "far.npy", np.array([[0.0, 0.0], [0.0, 99.0]]))
    (tmp_path / "bad.csv").write_text("0,1\n0,x\n")
    (tmp_path / "b.txt").write_text("0")
    cases = {
        "wide.npy": ["5 betas", "has 3"],
        "far.npy": ["row 2", "column 2", "beta1", "out of range"],
        "bad.csv": ["row 2", "column 2", "'x'"],
        "b.txt": ["npy, .npz or .csv"],
    }
    for name, words in cases.items():
        with pytest.raises(BodySourceError) as exc:
            read_betas(tmp_path / name, params)
        assert name in str(exc.value) and "\n" not in str(exc.value)
        for w in words:
            assert w in str(exc.value), str(exc.value)


def test_item_ids_hash_design_body_and_options():
    bodies = sample_anny(3, seed=0, parameters=ANNY_PARAMS)
    design = {"name": "d", "keypoints": {}}
    ids = [it.id for it in make_items(design, bodies)]
    assert len(set(ids)) == 3 and ids == [it.id for it in make_items(dict(design), bodies)]
    assert ids != [it.id for it in make_items({**design, "name": "e"}, bodies)]
    assert ids != [it.id for it in make_items(design, bodies, options=Options(export=("svg",)))]
    assert len(make_items(design, bodies + bodies[:1])) == 3  # the same body twice is one item


def test_items_take_the_designs_solver_unless_the_caller_names_one():
    """Options.config None is the design's own "solver" (else improved), made explicit in the item: the
    same ids as naming it, so a rerun skips what either way made; a caller's choice wins."""
    bodies = sample_anny(2, seed=0, parameters=ANNY_PARAMS)
    fitted = {"name": "d", "keypoints": {}, "solver": "fitted"}
    assert {it.options.config for it in make_items(fitted, bodies)} == {"fitted"}
    assert [it.id for it in make_items(fitted, bodies)] == [
        it.id for it in make_items(fitted, bodies, options=Options(config="fitted"))
    ]
    assert {it.options.config for it in make_items(fitted, bodies, options=Options(config="lengths"))} == {"lengths"}
    assert {it.options.config for it in make_items({"name": "d", "keypoints": {}}, bodies)} == {"improved"}


def test_journal_survives_a_torn_last_line(tmp_path):
    j = Journal(tmp_path)
    j.extend([{"id": "b", "status": "ok", "timings.body": 1.0}])
    j.extend([{"id": "a", "status": "error", "error": "x"}])
    j.close()
    with open(tmp_path / "manifest.jsonl", "a") as f:
        f.write('{"id": "c", "sta')  # a crash mid-write
    j = Journal(tmp_path)
    j.extend([{"id": "a", "status": "ok"}])
    j.close()
    rows = read_rows(tmp_path / "manifest.jsonl")
    assert [r["id"] for r in rows] == ["b", "a", "a"]
    assert set(completed(rows)) == {"a", "b"}
    assert [r["id"] for r in compact(tmp_path)] == ["a", "b"]
    assert comparable(read_rows(tmp_path / "manifest.jsonl")) == [
        {"id": "a", "status": "ok"},
        {"id": "b", "status": "ok"},
    ]
    assert json.loads((tmp_path / "manifest.jsonl").read_text().splitlines()[0])["id"] == "a"


def test_placement_recovers_a_rigid_motion():
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(1)
    uv = rng.random((30, 2))
    R = Rotation.from_euler("XYZ", [20, -35, 110], degrees=True).as_matrix()
    t = np.array([0.1, -2.0, 3.0])
    xyz = np.column_stack([uv, np.zeros(30)]) @ R.T + t
    R2, t2 = placement(uv, xyz)
    assert np.allclose(R2, R) and np.allclose(t2, t)


def test_parquet_beside_the_journal_where_pyarrow_is_installed(tmp_path):
    pq = pytest.importorskip("pyarrow.parquet")
    j = Journal(tmp_path)
    j.extend([{"id": "b", "status": "ok", "metrics.weft_mean_pct": 1.5}])
    j.extend([{"id": "a", "status": "error", "error": "x"}])
    j.close()
    compact(tmp_path)
    table = pq.read_table(tmp_path / "manifest.parquet").to_pylist()
    assert [r["id"] for r in table] == ["a", "b"] and table[1]["metrics.weft_mean_pct"] == 1.5
