"""Size charts (default, women's and men's EN 13402-3): stored fits within 1 cm, re-fits, names,
designs on a chart body and on an OBJ template."""

import argparse
import json

import numpy as np
import pytest
from conftest import sample
from test_body_obj import horse, write_obj

from core.body.charts import PUBLISHED
from core.body.made_to_measure import THIGH_MARGIN_CM, collisions, thigh_gap
from core.body.measure import measure
from core.body.registry import load_spec, resolve_body_files
from core.body.sizes import (
    CHART_NAMES,
    CHART_THIGH_GAP_CM,
    TOLERANCE_CM,
    chart_fit,
    chart_sizes,
    chart_tape_fit,
    check_size,
    fit_measurements,
    size_of,
    size_shape,
    size_targets,
)
from core.body.tape import tape_measures
from core.errors import BodyError, DesignError

CASES = [(c, s) for c in PUBLISHED for s in PUBLISHED[c].sizes]


def test_chart_names_and_errors():
    assert CHART_NAMES == ("default", "women", "men")
    assert check_size("m", "Women") == "women:M" and check_size("women:l") == "women:L"
    assert check_size("M") == "M" and check_size("default:XL") == "XL"
    assert chart_sizes("men") == ("XS", "S", "M", "L", "XL", "XXL")
    assert chart_sizes("women") == ("XS", "S", "M", "L", "XL", "XXL", "3XL", "4XL")
    with pytest.raises(BodyError, match="unknown size chart 'kids'; allowed: default, women, men"):
        check_size("M", "kids")
    with pytest.raises(BodyError, match="unknown size 'XXS' of chart 'women'; allowed: XS, S, M, L, XL, XXL, 3XL, 4XL"):
        check_size("XXS", "women")
    with pytest.raises(BodyError, match="is of chart 'men', not of chart 'women'"):
        check_size("men:M", "women")


def test_a_chart_names_bare_sizes_only():
    """size_of: the chart is the default of a bare size; a qualified size keeps its own chart."""
    assert size_of("l", "women") == "women:L" and size_of("men:L", "women") == "men:L"
    assert size_of("M", None) == "M" and size_of("women:M", None) == "women:M"
    with pytest.raises(BodyError, match="unknown size '5XL' of chart 'women'"):
        size_of("5XL", "women")


def test_charts_are_ordered_and_sourced():
    for c in PUBLISHED.values():
        assert "EN 13402-3" in c.title
        rows = list(c.sizes.values())
        for a, b in zip(rows, rows[1:]):
            assert b["chest"] > a["chest"] and b["waist"] > a["waist"]
        assert set(c.fitted["anny"]) == set(c.sizes)
    # German size tables: one height for the women's normal sizes, a taller man for a larger chest.
    assert {r["height"] for r in PUBLISHED["women"].sizes.values()} == {168.0}
    assert [r["height"] for r in PUBLISHED["men"].sizes.values()] == [166.7, 170.0, 174.0, 178.0, 182.0, 186.0]
    # The women's plus range reaches a bust of 130 cm and more.
    assert max(r["chest"] for r in PUBLISHED["women"].sizes.values()) >= 130.0


@pytest.mark.parametrize("chart,size", CASES)
def test_stored_fits_measure_within_1cm(anny, chart, size):
    """The stored Anny shape of each chart size, measured as a tailor measures (core.body.tape:
    bust at the bust points, natural waist, hip at the buttocks), is within 1 cm of every target,
    with the chart's gender phenotype, symmetric, and its thighs do not pass through each other."""
    shape = size_shape(anny, size, chart=chart)
    assert shape["gender"] == PUBLISHED[chart].start["gender"]
    targets = size_targets(size, chart)
    got = tape_measures(anny, None, list(targets), shape=shape)
    for k, want in targets.items():
        assert abs(got[k] - want) <= TOLERANCE_CM, (chart, size, k, got[k], want)
    assert not collisions(anny, shape)
    # Anny's phenotype blends alone are mirrored within 0.9 mm (a man at weight 1); the local changes
    # the fit uses are symmetric and add nothing to it.
    v = anny.vertices(shape)
    assert np.abs(v[anny.symmetry] * np.array([-1.0, 1.0, 1.0]) - v).max() < 1.5e-3


@pytest.mark.parametrize("size", ["3XL", "4XL"])
def test_plus_sizes_keep_their_thighs_apart_at_the_average_cup(anny, size):
    """The women's 3XL and 4XL, refitted with the chart fit's thigh gap (CHART_THIGH_GAP_CM, above
    made-to-measure's THIGH_MARGIN_CM) and the underbust local, keep their inner thighs at least
    0.6 cm apart (1.8 mm before: the pants' back legs collapsed in that crease) and Anny's average
    cup (4XL's cup 0.75 pulled the tops' side seams 3.4-6.4 mm apart); tests/test_templates_charts.py
    solves every template on them."""
    assert CHART_THIGH_GAP_CM > THIGH_MARGIN_CM
    shape = size_shape(anny, size, chart="women")
    assert thigh_gap(anny, anny.vertices(shape)) >= 0.6
    assert shape["cupsize"] == 0.5


def test_old_waist_definition_differs_where_documented(anny):
    """The waist at the landmark height (core.body.measure, the old chart definition) of the
    refitted women's L is some 6 cm more than its natural waist, which is the chart's 86.5 cm
    (docs/bodies.md's table lists both); before the refit the natural waist was 80.7 cm."""
    shape = size_shape(anny, "women:L")
    natural = tape_measures(anny, None, ["waist"], shape=shape)["waist"]
    old = measure(anny, anny.vertices(shape), ["waist"])["waist"]
    assert abs(natural - 86.5) <= TOLERANCE_CM and old - natural > 4.0


@pytest.mark.parametrize("case", sample(CASES, 2, seed=14))
def test_refit_lands_within_1cm(anny, case):
    """chart_tape_fit re-makes a stored fit from its phenotypes with every local change at 0 (the
    population's body): within 1 cm on the tape measures, without self-intersection."""
    chart, size = case
    stored = size_shape(anny, size, chart=chart)
    fit = chart_tape_fit(anny, size, chart, start={k: v for k, v in stored.items() if k in anny.shape_parameters()})
    assert fit.ok, fit.summary()


def test_women_xl_needs_local_changes(anny):
    """Women's XL (113/97/120 cm, a 23 cm hip-waist drop) is beyond Anny's phenotypes: from its stored
    shape's phenotypes the phenotype fit misses by more than 1 cm; with the bust, waist and hip
    local changes moving too it lands within 1 cm, and the stored shape carries them (small,
    within -1 .. 1), symmetric: the left and right halves mirror within a millimetre."""
    c = PUBLISHED["women"]
    stored = size_shape(anny, "XL", chart="women")
    local = {k: v for k, v in stored.items() if k in anny.local_change_parameters()}
    assert set(local) == set(c.local) and all(0 < abs(v) < 1 for v in local.values())
    phen = {k: v for k, v in stored.items() if k not in local}
    plain = fit_measurements(
        anny, c.sizes["XL"], start=phen, parameters=list(c.parameters) + ["cupsize"], bounds=c.bounds
    )
    assert not plain.ok and plain.achieved["hip"] - plain.achieved["waist"] < 20.0
    fit = fit_measurements(
        anny, c.sizes["XL"], start=phen, parameters=list(c.parameters) + list(c.local), bounds=c.bounds
    )
    assert fit.ok, fit.summary()
    v = anny.vertices(stored)
    assert np.abs(v[anny.symmetry] * np.array([-1.0, 1.0, 1.0]) - v).max() < 1e-3


@pytest.mark.parametrize("chart", ["women", "men"])
def test_restarts_bring_xs_in_reach(anny, chart):
    """From the chart's start alone the XS fit stops on the wrong side of a blend's kink and
    misses; chart_fit's restarts land it within 1 cm."""
    c = PUBLISHED[chart]
    first = fit_measurements(anny, c.sizes["XS"], start=c.start, parameters=c.parameters, bounds=c.bounds)
    assert not first.ok
    seen = []
    fit = chart_fit(anny, "XS", chart, progress=lambda f, m: seen.append((f, m)))
    assert fit.ok, fit.summary()
    assert max(abs(fit.achieved[k] - v) for k, v in fit.targets.items()) <= TOLERANCE_CM
    # the restarts share one rising bar, each labelled with its place among the attempts
    fractions = [f for f, _ in seen]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    assert any("fit 2 of" in m for _, m in seen)


def test_women_and_men_differ_where_the_chart_says(anny):
    w = measure(anny, anny.vertices(size_shape(anny, "women:M")))
    m = measure(anny, anny.vertices(size_shape(anny, "men:M")))
    assert w["hip"] - w["waist"] > m["hip"] - m["waist"] + 5  # the women's chart's hip drop


# -- designs -------------------------------------------------------------------------------
def _design(body):
    with open("core/data/designs/top_short_sleeve.json") as f:
        d = json.load(f)
    d["body"] = body
    return d


def test_design_body_chart(anny):
    from core.design import load_design

    design = load_design(_design({"chart": "women", "shape": "M"}))
    assert design.body["shape"] == "women:M" and design.body["chart"] == "women"
    assert load_design(design.to_json()).body == design.body  # saved and read back alike
    with pytest.raises(DesignError, match=r"body\.chart.*default, women, men.*kids"):
        load_design(_design({"chart": "kids", "shape": "M"}))
    with pytest.raises(DesignError, match=r"body\.shape.*chart women \(XS, S, M, L, XL, XXL, 3XL, 4XL\).*5XL"):
        load_design(_design({"chart": "women", "shape": "5XL"}))


def test_prepare_and_transfer_on_a_chart_body(anny):
    """A design on women:M is cut on that body; transfer "L" means the design's chart's L."""
    import core.workflows as wf

    prep = wf.prepare(_design({"chart": "women", "shape": "M"}), body=anny)
    assert prep.cut.body["shape"] == "women:M"
    np.testing.assert_allclose(prep.reference, anny.vertices(size_shape(anny, "women:M")), atol=1e-9)
    assert wf.size_name(prep, "l") == "women:L" and wf.size_name(prep, "men:M") == "men:M"
    with pytest.raises(BodyError, match="allowed: XS, S, M, L, XL, XXL, 3XL, 4XL"):
        wf.size_name(prep, "5XL")
    run = wf.transfer(prep, "L", iterations=3)
    assert run.pattern.report["size"] == "women:L"
    assert run.pattern.body["shape"] == size_shape(anny, "women:L")


@pytest.fixture
def horse_design(tmp_path):
    """A box horse OBJ with landmarks and blend shapes in a subfolder, and a design naming them
    relative to the design file."""
    (tmp_path / "bodies").mkdir()
    v, quads, owner = horse()
    write_obj(tmp_path / "bodies" / "horse.obj", v, quads)
    belly = np.zeros((len(v), 3))
    belly[(np.array(owner) == "torso") & (v[:, 2] < 1.0), 2] = -0.1
    np.savez(tmp_path / "bodies" / "shapes.npz", names=np.array(["belly"]), deltas=belly[None])
    (tmp_path / "bodies" / "marks.json").write_text(json.dumps({"withers": 5, "nose": 40}))
    body = {"model": "bodies/horse.obj", "landmarks": "bodies/marks.json", "blendshapes": "bodies/shapes.npz"}
    return tmp_path, body


def test_obj_template_through_a_design(horse_design):
    from core.design import load_design

    folder, body = horse_design
    design = load_design(_design(dict(body)))
    assert design.body["shape"] is None  # an OBJ template is its own reference body
    spec = resolve_body_files(design.body, folder)
    assert spec["model"] == str(folder / "bodies" / "horse.obj")
    model = load_spec(spec)
    assert set(model.landmarks) == {"withers", "nose"} and list(model.shape_parameters()) == ["belly"]
    from core.body.instance import spec_instance

    V, _ = spec_instance({**spec, "shape": {"belly": 1.0}})
    assert V.shape == model.vertices().shape and (V[:, 2] < model.vertices()[:, 2] - 0.05).sum() == 4
    # A chart size on a template without the girth landmarks says what is missing.
    with pytest.raises(BodyError, match="has no bust_left.*landmarks.*body.landmarks"):
        size_shape(model, "M")
    for key, value, message in (("landmarks", "marks.txt", "a .json file"), ("up", "x", "'z' or 'y'")):
        with pytest.raises(DesignError, match=rf"body\.{key}.*{message}"):
            load_design(_design({**body, key: value}))
    with pytest.raises(DesignError, match=r"body\.landmarks.*only an OBJ template"):
        load_design(_design({"model": "anny", "landmarks": "m.json"}))


def test_cli_body_chart(tmp_path):
    from core.cli import body as body_cli

    def ease_body(argv):
        parser = argparse.ArgumentParser(prog="ease")
        body_cli.add_parser(parser.add_subparsers(dest="command"))
        args = parser.parse_args(["body", *argv, "--quiet"])
        return args.func(args)

    out = tmp_path / "w.obj"
    assert ease_body(["--chart", "women", "--size", "S", "--out", str(out)]) == 0
    with pytest.raises(BodyError, match="--size: unknown size '5XL' of chart 'women'; allowed: XS, S, M, L, XL"):
        ease_body(["--chart", "women", "--size", "5XL", "--out", str(out)])
    with pytest.raises(BodyError, match="--chart: unknown size chart 'kids'; allowed: default, women, men"):
        ease_body(["--chart", "kids", "--size", "M", "--out", str(out)])


def test_addon_chart_presets(bpy_session, blender, anny):
    """The add-on's chart beside the size: Apply Size on the women's chart gives women:M; a size
    the chart lacks is refused and the body stays."""
    bpy = bpy_session["bpy"]
    blender.reset()
    assert bpy.ops.ease.add_body(source="DEFAULT") == {"FINISHED"}
    s = bpy.context.scene.ease
    assert {i.identifier for i in s.bl_rna.properties["chart"].enum_items} == set(CHART_NAMES)
    s.chart = "women"
    assert bpy.ops.ease.set_size(size="M") == {"FINISHED"}
    assert np.allclose(blender.verts(s.body), anny.vertices(size_shape(anny, "women:M")), atol=1e-5)
    assert s.body["ease_size"] == "women:M"
    before = blender.verts(s.body).copy()
    with pytest.raises(RuntimeError, match="unknown size '5XL' of chart 'women'"):
        bpy.ops.ease.set_size(size="5XL")
    assert np.allclose(blender.verts(s.body), before)
    s.chart = "default"
