"""``ease cut``: writes its files (atomically), reloads, is deterministic; bad designs write nothing."""

import argparse
import json

import numpy as np
import pytest
import scipy.sparse as sp

from core.cli.cut import add_parser
from core.cut.io import load_cut, save_cut
from core.cut.output import obj_text
from core.cut.types import GarmentCut, Panel, Seam
from core.design.templates import TEMPLATES, template_path
from core.errors import BodyError, CutError, DesignError

SHIRT = template_path("shirt_long_sleeve")


def ease_cut(*argv):
    parser = argparse.ArgumentParser(prog="ease")
    add_parser(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["cut", *map(str, argv)])
    return args.func(args)


def test_help_lists_the_options(capsys):
    with pytest.raises(SystemExit):
        ease_cut("--help")
    out = capsys.readouterr().out
    for opt in ("--out", "--size", "--pose", "--body", "--no-png"):
        assert opt in out


def test_cut_writes_its_files_and_reloads(tmp_path):
    out = tmp_path / "cut"
    assert ease_cut(SHIRT, "--out", out, "--quiet") == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == ["cut.json", "cut.png", "cut_embedding.npz", "design.json", "panels.obj"]
    assert (out / "cut.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temp dirs left
    cut = load_cut(out)
    assert len(cut.panels) == 6 and len(cut.seams) == 12
    assert cut.garments == {"shirt": "upper"} and len(cut.pins["shirt"]) > 0
    assert cut.materials["eps_weft"] == 1.1 and cut.body["shape"] == "M"
    assert all(np.allclose(p.ease, 1.2) for p in cut.panels)
    # OBJ: every garment vertex, one group per panel, faces matching the cut
    text = (out / "panels.obj").read_text()
    groups = [l.split()[1] for l in text.splitlines() if l.startswith("g ")]
    assert groups == [p.name for p in cut.panels]
    assert sum(l.startswith("v ") for l in text.splitlines()) == cut.n_vertices
    assert sum(l.startswith("f ") for l in text.splitlines()) == sum(len(p.faces) for p in cut.panels)
    design = json.loads((out / "design.json").read_text())
    assert design["format"] == "ease-design" and design["name"] == "long-sleeve shirt"
    # same inputs, same outputs
    again = tmp_path / "again"
    assert ease_cut(SHIRT, "--out", again, "--quiet", "--no-png") == 0
    assert (again / "cut.json").read_bytes() == (out / "cut.json").read_bytes()
    assert (again / "panels.obj").read_bytes() == (out / "panels.obj").read_bytes()


def test_cut_on_another_size_shown_on_a_pose(tmp_path):
    from core.body import load_body
    from core.body.sizes import size_shape

    out = tmp_path / "xl"
    assert ease_cut(template_path("skirt"), "--out", out, "--size", "XL", "--pose", "P3", "--quiet", "--no-png") == 0
    cut = load_cut(out)
    assert cut.body["shape"] == "XL" and cut.body["pose"] == "A"  # cut on the reference pose
    assert [p.name for p in cut.panels] == ["skirt.front", "skirt.back"]
    body = load_body("anny")
    X = cut.positions(body.vertices(size_shape(body, "XL"), "P3"))  # ... shown sitting
    V = np.array(
        [[float(x) for x in l.split()[1:]] for l in (out / "panels.obj").read_text().splitlines() if l.startswith("v ")]
    )
    assert np.allclose(V, X, atol=1e-6)


def test_size_of_a_chart_and_unknown_sizes(tmp_path):
    """``--size women:M`` cuts on that chart's size; an unknown size names --size and the choices."""
    out = tmp_path / "w"
    assert ease_cut(template_path("skirt"), "--out", out, "--size", "women:M", "--quiet", "--no-png") == 0
    assert load_cut(out).body["shape"] == "women:M"
    for size, words in (("XXL", "XS, S, M, L, XL"), ("women:5XL", "S, M, L"), ("kids:M", "chart")):
        with pytest.raises(BodyError) as e:
            ease_cut(template_path("skirt"), "--out", tmp_path / "bad", "--size", size, "--quiet")
        assert str(e.value).startswith("--size:") and words in str(e.value), e.value
    assert not (tmp_path / "bad").exists()


def test_automatic_darts_are_written_back(tmp_path):
    """``ease cut`` of a design asking for automatic darts writes them into design.json as
    explicit darts (the designer edits them there); cutting that file again gives the same cut."""
    d = TEMPLATES["blouse_fitted"]()
    d["garments"][0]["panels"][0]["darts"] = {"auto": {"max_count": 1, "max_intake": 0.08}}
    src = tmp_path / "auto.json"
    src.write_text(json.dumps(d))
    out = tmp_path / "cut"
    assert ease_cut(src, "--out", out, "--quiet", "--no-png") == 0
    placed = json.loads((out / "design.json").read_text())["garments"][0]["panels"][0]["darts"]
    assert isinstance(placed, list) and len(placed) == 1 and placed[0]["apex"] == "bust_left"
    again = tmp_path / "again"
    assert ease_cut(out / "design.json", "--out", again, "--quiet", "--no-png") == 0
    assert (again / "cut.json").read_bytes() == (out / "cut.json").read_bytes()


def test_bad_design_writes_nothing(tmp_path):
    d = TEMPLATES["shirt_long_sleeve"]()
    d["garments"][0]["panels"][0]["ease"] = {"value": 7}
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(d))
    out = tmp_path / "out"
    with pytest.raises(DesignError) as e:
        ease_cut(bad, "--out", out)
    assert e.value.path == "garments[0].panels[0].ease.value"
    assert not out.exists()
    # an existing output folder is left exactly as it was
    out.mkdir()
    (out / "keep.txt").write_text("old")
    d = TEMPLATES["shirt_long_sleeve"]()
    d["garments"][0]["lines"][0]["points"][0] = "nek_front"
    bad.write_text(json.dumps(d))
    with pytest.raises(DesignError):
        ease_cut(bad, "--out", out)
    assert sorted(p.name for p in out.iterdir()) == ["keep.txt"]


def test_cut_error_writes_nothing(tmp_path):
    # without side seams front and back are one region: the engine refuses
    d = TEMPLATES["top_sleeveless"]()
    g = d["garments"][0]
    g["lines"] = [l for l in g["lines"] if l["name"] != "side_left"]
    bad = tmp_path / "open.json"
    bad.write_text(json.dumps(d))
    out = tmp_path / "out"
    with pytest.raises(CutError):
        ease_cut(bad, "--out", out)
    assert not out.exists()


def _synthetic_cut():
    E = sp.csr_matrix(np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0.5, 0.5], [0, 0, 0, 1.0]]))
    a = Panel(
        name="g.a",
        garment="g",
        vertex_ids=np.array([0, 1, 2]),
        faces=np.array([[0, 1, 2]]),
        warp_dir=np.array([[0, 0, 1.0]]),
        ease=np.array([1.3]),
        boundary=[np.array([0, 1, 2])],
    )
    b = Panel(
        name="g.b",
        garment="g",
        vertex_ids=np.array([1, 2, 3]),
        faces=np.array([[0, 2, 1]]),
        warp_dir=np.array([[0, 0, 1.0]]),
        ease=np.array([2.0]),
        boundary=[np.array([0, 2, 1])],
        body_part="arm",
        mirror_of="g.a",
    )
    return GarmentCut(
        body={"model": "anny", "shape": {"weight": 0.7}, "pose": "P1"},
        embedding=E,
        panels=[a, b],
        seams=[Seam("g.s", "g.a", "g.b", np.array([1, 2]), np.array([0, 1]))],
        garments={"g": "upper"},
        pins={"g": np.array([0, 1])},
        hems={"g.a": [np.array([2, 0])]},
        materials={"fabric": "cotton", "eps_weft": 1.2},
    )


def test_io_round_trip(tmp_path):
    cut = _synthetic_cut()
    save_cut(cut, tmp_path)
    back = load_cut(tmp_path)
    assert (back.embedding != cut.embedding).nnz == 0
    for p, q in zip(cut.panels, back.panels):
        for f in ("vertex_ids", "faces", "warp_dir", "ease"):
            assert np.array_equal(getattr(p, f), getattr(q, f))
        assert p.name == q.name and p.body_part == q.body_part and p.mirror_of == q.mirror_of
        assert all(np.array_equal(x, y) for x, y in zip(p.boundary, q.boundary))
    assert np.array_equal(back.seams[0].verts_b, cut.seams[0].verts_b)
    assert back.body == cut.body and back.materials == cut.materials and back.garments == cut.garments
    assert np.array_equal(back.pins["g"], cut.pins["g"]) and np.array_equal(back.hems["g.a"][0], [2, 0])
    text = obj_text(cut, cut.positions(np.eye(4)[:, :3]))
    assert text.count("\ng ") == 2 and text.count("\nf ") == 2


def test_load_cut_errors(tmp_path):
    with pytest.raises(CutError, match="missing"):
        load_cut(tmp_path)
    save_cut(_synthetic_cut(), tmp_path)
    (tmp_path / "cut.json").write_text('{"format": "ease-pattern", "version": 1}')
    with pytest.raises(CutError, match="ease-cut"):
        load_cut(tmp_path)


def _shirt_lines(d):
    return d["garments"][0]["lines"]


def _drop_line(name):
    def edit(d):
        d["garments"][0]["lines"] = [l for l in _shirt_lines(d) if l["name"] != name]

    return edit


def _set(getter, key, value):
    def edit(d):
        getter(d)[key] = value

    return edit


def _traced_sleeve(length):
    """The long sleeve's cuff placed by a traced length (m), not by its share of the way to the wrist."""

    def edit(d):
        d["parameters"]["sleeve_length"] = {"value": length, "kind": "length"}
        trace = {"from": "armhole_top_left", "along": "arm_left", "length": "$sleeve_length"}
        d["keypoints"]["cuff_level_left"] = {"trace": trace}

    return edit


# issue 3's error list, each through `ease cut` on the long-sleeve shirt: (edit, error, JSON path or
# None, words the message must contain - the design element it names)
ERROR_CASES = {
    "unknown landmark": (
        _set(lambda d: _shirt_lines(d)[0]["points"], 1, "nek_left"),
        DesignError,
        "garments[0].lines[0].points[1]",
        ["'nek_left'", "neck_left"],
    ),
    "seamline does not close (open neckline)": (
        _set(lambda d: _shirt_lines(d)[0], "closed", False),
        CutError,
        None,
        ["'shirt.front'", "does not close", "'shirt.neckline'"],
    ),
    "seamline does not close (side seam stops at the waist)": (
        _set(lambda d: _shirt_lines(d)[4], "points", ["armhole_under_left", "waist_left"]),
        CutError,
        None,
        ["'shirt.front'", "'shirt.back'", "does not close", "'shirt.side_left'"],
    ),
    "missing seamline": (_drop_line("shoulder_left"), CutError, None, ["'shirt.front'", "'shirt.back'", "missing"]),
    "seamlines cross": (
        lambda d: _shirt_lines(d).append({"name": "belt", "points": ["chest_front", "chest_back"], "role": "seam"}),
        CutError,
        None,
        ["'shirt.belt'", "'shirt.side_", "cross"],
    ),
    "panel with no faces": (
        lambda d: d["garments"][0]["panels"].append({"name": "pocket", "seed": "navel", "body_part": "torso"}),
        CutError,
        None,
        ["'shirt.pocket'", "no faces", "'shirt.front'"],
    ),
    "keypoint off the body": (
        _set(lambda d: d["keypoints"], "chest_front", {"triangle": 10**7, "bary": [1, 0, 0]}),
        DesignError,
        "keypoints.chest_front.triangle",
        ["off the body"],
    ),
    "keypoint not on its triangle": (
        _set(lambda d: d["keypoints"], "chest_front", {"triangle": 5, "bary": [1.5, -0.5, 0]}),
        DesignError,
        "keypoints.chest_front.bary[0]",
        ["1.5"],
    ),
    "length leaves the body part": (
        _traced_sleeve(0.9),
        DesignError,
        "parameters.sleeve_length",
        ["leaves the body part", "arm_left"],
    ),
    "ease NaN": (
        _set(lambda d: d["garments"][0]["panels"][1]["ease"], "value", float("nan")),
        DesignError,
        "garments[0].panels[1].ease.value",
        ["panel 'back'", "NaN"],
    ),
    "ease below 0.8": (
        _set(lambda d: d["garments"][0]["panels"][1]["ease"], "value", 0.3),
        DesignError,
        "garments[0].panels[1].ease.value",
        ["panel 'back'", "0.8..4.0"],
    ),
    "ease gradient above 4": (
        _set(
            lambda d: d["garments"][0]["panels"],
            2,
            {
                "name": "sleeve_front_left",
                "seed": "sleeve_front_mid_left",
                "body_part": "arm",
                "ease": {"from": 1.0, "to": 4.5, "axis": "z"},
            },
        ),
        DesignError,
        "garments[0].panels[2].ease.to",
        ["panel 'sleeve_front_left'", "4.5"],
    ),
    "ease per-triangle value": (
        _set(
            lambda d: d["garments"][0]["panels"][0],
            "ease",
            {"per_triangle": {"triangles": [0, 1], "values": [1.2, float("inf")]}},
        ),
        DesignError,
        "garments[0].panels[0].ease.per_triangle.values[1]",
        ["panel 'front'"],
    ),
}


@pytest.mark.parametrize("case", list(ERROR_CASES))
def test_each_bad_input_is_named_and_writes_nothing(case, tmp_path):
    edit, error, path, words = ERROR_CASES[case]
    d = TEMPLATES["shirt_long_sleeve"]()
    edit(d)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(d))  # NaN / Infinity as JSON extensions
    out = tmp_path / "out"
    with pytest.raises(error) as e:
        ease_cut(bad, "--out", out, "--quiet")
    if path is not None:
        assert e.value.path == path
    for w in words:
        assert w in str(e.value), (w, str(e.value))
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json"]  # no temporary leftovers
