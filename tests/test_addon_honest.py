"""An add-on that neither crashes nor lies (issue 32): a template switch leaves a whole scene, a
template says what it did to the body, the size controls offer only the chart's sizes, a refused
parameter is not shown as if it were used, X-mirror mirrors a stroke (not halves it) and turning
it on while Live runs re-solves.

Panels are drawn into a recording layout (:class:`Layout`): what a designer would see, headless.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

SHIRT = "top_short_sleeve.json"  # sleeves: a mirrored design with more panels than the top
TOP = "top_sleeveless.json"
BLOUSE = "blouse_fitted.json"  # the women's chart


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    return blender.reset(body=True)


class Layout:
    """A UILayout stand-in that records what a panel draws: ``props`` (property names),
    ``enums`` ((property, value) of single enum buttons), ``labels``, ``operators``."""

    def __init__(self, log=None):
        self.log = log if log is not None else {"props": [], "enums": [], "labels": [], "operators": []}
        self.enabled = True

    def _child(self, *_a, **_k):
        return Layout(self.log)

    row = column = box = split = _child

    def separator(self, *_a, **_k):
        pass

    def prop(self, data, name, **_kw):
        self.log["props"].append(name)

    def prop_enum(self, data, name, value, **_kw):
        self.log["enums"].append((name, value))

    def label(self, text="", **_kw):
        self.log["labels"].append(text)

    def operator(self, idname, **_kw):
        self.log["operators"].append(idname)

        class _Props:
            pass

        return _Props()


def _draw(blender, panel: str) -> dict:
    cls = getattr(blender.mod("panels"), panel)
    fake = type("Panel", (), {})()
    fake.layout = Layout()
    cls.draw(fake, blender.bpy.context)
    return fake.layout.log


def _seam_count(blender, cut) -> int:
    """Vertices of the seamlines object ``cut`` gives (every panel boundary loop, closed)."""
    build = blender.mod("build")
    return sum(len(loop) for loop in build.seam_loops(cut))


def _check_whole(blender, template):
    """The scene holds ``template`` throughout: design, seamlines of its cut on the body, markers."""
    from scipy.spatial import cKDTree

    bpy = blender.bpy
    s = bpy.context.scene.ease
    data = blender.mod("data")
    want = json.loads((data.template_dir() / template).read_text())["name"]
    assert json.loads(s.design_json)["name"] == want
    cut = data.current_cut(bpy.context)
    seams = blender.objects("seamlines")
    assert len(seams) == 1 and len(seams[0].data.vertices) == _seam_count(blender, cut)
    d, _ = cKDTree(blender.verts(s.body)).query(blender.verts(seams[0]))
    assert d.max() < 0.03
    assert [o.name for o in blender.objects("body")] == ["EASE Body"]


@pytest.mark.parametrize("first, then", [(SHIRT, TOP), (SHIRT, BLOUSE), (BLOUSE, SHIRT)])
def test_template_switch_keeps_the_scene_whole(blender, first, then):
    """Shirt -> top or blouse raised IndexError in sync.refresh_attachments (the old design's
    seamline ids indexed with the new cut), leaving the body reshaped and the old design."""
    bpy = blender.bpy
    blender.reset(body=True, design=first)
    assert blender.run(bpy.ops.ease.load_template, template=then) == {"FINISHED"}
    _check_whole(blender, then)
    # the seamlines follow the body's next move (a pose) with the new design's cut
    assert bpy.ops.ease.set_pose(pose="P1") == {"FINISHED"}
    _check_whole(blender, then)
    assert bpy.ops.ease.set_pose(pose="A") == {"FINISHED"}


def test_switch_after_re_adding_the_body(blender):
    bpy = blender.bpy
    blender.reset(body=True, design=SHIRT)
    assert bpy.ops.ease.add_body(source="DEFAULT") == {"FINISHED"}
    assert blender.run(bpy.ops.ease.load_template, template=TOP) == {"FINISHED"}
    _check_whole(blender, TOP)


def test_template_says_what_it_does_to_the_body(blender, anny):
    """A women:M body, then a template of the default chart's M: the body takes the design's
    size and the Body panel says so (it kept saying women:M while the body was the default M)."""
    from core.body.instance import body_instance

    bpy = blender.bpy
    blender.reset(body=True)
    s = bpy.context.scene.ease
    s.chart = "women"
    s.size = "M"
    assert bpy.ops.ease.set_size() == {"FINISHED"}
    assert s.body["ease_size"] == "women:M"
    assert bpy.ops.ease.load_template(template=TOP) == {"FINISHED"}
    assert np.allclose(blender.verts(s.body), body_instance(anny, "M"), atol=1e-5)
    assert (s.chart, s.size, s.body["ease_size"]) == ("default", "M", "M")
    assert "Body size: M" in _draw(blender, "EASE_PT_body")["labels"]
    assert "height 183.5 cm" in s.measurements_report
    assert {i.name: i.value for i in s.shape} == pytest.approx(json.loads(s.body["ease_shape"]), abs=1e-6)
    # a women's design on it: the body and the panel go to women:M together
    assert bpy.ops.ease.load_template(template=BLOUSE) == {"FINISHED"}
    assert np.allclose(blender.verts(s.body), body_instance(anny, "women:M"), atol=1e-5)
    assert (s.chart, s.size, s.body["ease_size"]) == ("women", "M", "women:M")


def _short_chart(data):
    """(a chart, a size of another chart it lacks), the chart with the fewest sizes."""
    from core.body.sizes import CHARTS

    chart = min(CHARTS, key=lambda c: len(data.chart_sizes(c)))
    lacks = [z for z in data.all_sizes() if z not in data.chart_sizes(chart)]
    assert lacks, "every chart has every size: nothing to offer wrongly"
    return chart, lacks[-1]


def test_body_panel_has_the_chart_selector_and_only_its_sizes(blender):
    bpy = blender.bpy
    data = blender.mod("data")
    blender.reset(body=True)
    s = bpy.context.scene.ease
    chart, lacks = _short_chart(data)
    log = _draw(blender, "EASE_PT_body")
    assert "chart" in log["props"]
    assert [v for p, v in log["enums"] if p == "size"] == list(data.chart_sizes(s.chart))
    s.chart = next(c for c in ("default", "women", "men") if lacks in data.chart_sizes(c))
    s.size = lacks
    s.chart = chart  # it has no such size: the preset moves to the chart's nearest
    assert s.size == data.chart_sizes(chart)[-1]
    log = _draw(blender, "EASE_PT_body")
    assert [v for p, v in log["enums"] if p == "size"] == list(data.chart_sizes(chart))
    assert bpy.ops.ease.set_size() == {"FINISHED"}
    want = s.size if chart == "default" else f"{chart}:{s.size}"
    assert s.body["ease_size"] == want
    s.chart = "default"


def test_fit_panel_offers_the_design_charts_sizes(blender):
    """The Fit panel offered XL on every chart; on the women's chart Transfer then failed with
    "unknown size 'XL'". Now it offers the design's chart's sizes and greys out any other."""
    bpy = blender.bpy
    data = blender.mod("data")
    blender.reset(body=True)
    s = bpy.context.scene.ease
    sizes = data.chart_sizes("default")  # the top's chart
    lacks = [z for z in data.all_sizes() if z not in sizes]
    assert lacks
    s.fit_size = lacks[-1]
    assert bpy.ops.ease.load_template(template=TOP) == {"FINISHED"}
    assert s.fit_size == sizes[-1]  # not on the design's chart: its nearest
    log = _draw(blender, "EASE_PT_fit")
    assert [v for p, v in log["enums"] if p == "fit_size"] == list(sizes)
    s.fit_size = lacks[-1]  # a script sets it anyway
    assert not bpy.ops.ease.transfer_size.poll()
    why = blender.mod("operators_base").missing(bpy.context, ("body", "design", "fit_size"))
    assert lacks[-1] in why and "default" in why and ", ".join(sizes) in why
    s.fit_size = "L"
    assert bpy.ops.ease.transfer_size.poll()
    # a design of another chart: its sizes, and the panel names the chart
    assert bpy.ops.ease.load_template(template=BLOUSE) == {"FINISHED"}
    log = _draw(blender, "EASE_PT_fit")
    assert [v for p, v in log["enums"] if p == "fit_size"] == list(data.chart_sizes("women"))
    assert any("women" in t for t in log["labels"])


def test_out_of_range_parameter_is_refused_where_it_is_set(blender):
    """The slider kept the value while the design kept the old one, and the error went to the
    Drape panel's status line."""
    bpy = blender.bpy
    blender.reset(body=True, design=TOP)
    s = bpy.context.scene.ease
    item = s.design_params[0]
    design = blender.mod("data").current_design(bpy.context)
    old = design.parameters[item.name].value
    text = s.design_json
    s.drape_status = ""
    item.value = design.parameters[item.name].max + 0.5  # the slider's live re-cut refuses it
    assert item.value == pytest.approx(old)  # the slider shows what the design uses
    assert s.design_json == text
    assert item.name in s.design_status and "refused" in s.design_status
    assert s.drape_status == ""
    log = _draw(blender, "EASE_PT_design")
    assert s.design_status in log["labels"]
    # the operator says the same and leaves the design
    r = blender.run(bpy.ops.ease.set_parameter, name=item.name, value=design.parameters[item.name].max + 1)
    assert "ERROR" in r and item.name in r["ERROR"] and s.design_json == text
    # a value it takes clears the message
    assert bpy.ops.ease.set_parameter(name=item.name, value=old) == {"FINISHED"}
    assert s.design_status == ""


def _left_patch(blender, ease):
    """``ease`` painted (as data) on a 6 cm patch of the garment's left side (+X) only; the
    patch's vertices and their mirror vertices."""
    bpy = blender.bpy
    obj = bpy.context.scene.ease.body
    data, ramp = blender.mod("data"), blender.mod("ramp")
    cut = data.current_cut(bpy.context)
    on = np.zeros(len(obj.data.vertices), dtype=bool)
    on[np.unique(cut.embedding.tocsr().indices)] = True
    verts = blender.verts(obj).astype(np.float64)
    sym = np.asarray(data.state.body_model("anny").symmetry)
    centre = verts[np.flatnonzero(on & (verts[:, 0] > 0.08))[0]]
    patch = (np.linalg.norm(verts - centre, axis=1) < 0.06) & on & (verts[:, 0] > 0.02)
    lo, hi = data.layer_range(obj, bpy.context.scene)
    e = data.vertex_ease(obj, bpy.context.scene)
    e[patch] = ease
    obj.data.color_attributes["ease"].data.foreach_set(
        "color", ramp.ease_to_color(e, lo, hi).astype(np.float32).ravel()
    )
    obj.data.update()
    return patch, sym[patch]


def test_x_mirror_mirrors_a_one_sided_stroke(blender):
    """With X-mirror on, a 1.8 patch on one side became 1.5 on both (averaged with the 1.2 of
    its mirror); Blender's paint mirror paints 1.8 on both."""
    bpy = blender.bpy
    blender.reset(body=True, design=TOP)
    assert bpy.ops.ease.ease_uniform(whole_body=True, ease=1.2) == {"FINISHED"}
    assert bpy.ops.ease.ease_to_design() == {"FINISHED"}
    patch, mirror = _left_patch(blender, 1.8)
    me = bpy.context.scene.ease.body.data
    me.use_mirror_x = True
    try:
        assert bpy.ops.ease.ease_to_design() == {"FINISHED"}
    finally:
        me.use_mirror_x = False
    data = blender.mod("data")
    layer = data.vertex_ease(bpy.context.scene.ease.body, bpy.context.scene)
    assert np.allclose(layer[mirror], 1.8, atol=1e-5)  # the layer shows the mirrored stroke
    design = data.design_vertex_ease(bpy.context)
    faces = blender.mod("convert").get_triangles(me)
    inner = patch[faces].all(axis=1)  # triangles inside the patch
    inner_m = np.zeros(len(me.vertices), dtype=bool)
    inner_m[mirror] = True
    inner_m = inner_m[faces].all(axis=1)
    tri = data.triangle_ease(bpy.context.scene.ease.body, bpy.context.scene)
    assert np.allclose(tri[inner], 1.8, atol=1e-5) and np.allclose(tri[inner_m], 1.8, atol=1e-5)
    assert design[patch].max() == pytest.approx(1.8, abs=1e-5)
    assert design[mirror].max() == pytest.approx(1.8, abs=1e-5)


def test_x_mirror_on_while_live_runs_resolves(blender):
    """Turning X-mirror on while Live ran re-solved nothing and said "converged" over an
    asymmetric pattern. Now the tick sees the mirror, re-solves, and converges to the cold
    solve of the symmetric field."""
    from core.design.mirror import face_symmetry

    bpy = blender.bpy
    live, data = blender.mod("live"), blender.mod("data")
    blender.reset(body=True, design=TOP, pattern=True)
    s = bpy.context.scene.ease
    me = s.body.data
    me.use_mirror_x = False
    s.live = True
    try:
        _left_patch(blender, 1.6)

        def converge():
            for _ in range(500):
                if live.step(bpy.context)["converged"]:
                    return
            raise AssertionError("live mode did not converge")

        converge()
        field = live._field(s.body, bpy.context.scene)
        fs = face_symmetry(blender.mod("convert").get_triangles(me), np.asarray(data.state.body_model("anny").symmetry))
        has = fs >= 0
        assert np.abs(field[has] - field[fs[has]]).max() > 0.1  # asymmetric as painted
        me.use_mirror_x = True
        out = live.step(bpy.context)
        assert out["changed"] and not out["converged"]
        assert s.live_status.startswith("converging")
        converge()
        assert s.live_status.startswith("converged")
        field = live._field(s.body, bpy.context.scene)
        assert np.abs(field[has] - field[fs[has]]).max() < 1e-9  # symmetric now
        session = live.session_for(bpy.context)
        cold = session.cold_pattern(*live.targets(s.body, bpy.context.scene))
        stored = data.stored_pattern(bpy.context.scene)
        for p, q in zip(cold.panels, stored.panels):
            assert np.allclose(np.asarray(q.uv), p.uv, rtol=0, atol=1e-9)
    finally:
        me.use_mirror_x = False
        s.live = False


def test_operators_push_an_undo_step_as_the_ui_calls_them(blender):
    """A button press runs the operator with an undo push (``undo=True`` from Python): each EASE
    operator that changes the scene is one undo step, so Ctrl+Z takes back exactly it."""
    bpy = blender.bpy
    blender.reset(body=True, design=TOP)
    E = lambda: bpy.context.scene.ease  # noqa: E731  (undo rebuilds the data: fetch afresh)
    name = E().design_params[0].name
    steps = [
        (bpy.ops.ease.set_size, dict(size="S"), lambda: E().body.get("ease_size")),
        (bpy.ops.ease.set_pose, dict(pose="P1"), lambda: E().body.get("ease_pose")),
        (
            bpy.ops.ease.ease_uniform,
            dict(whole_body=True, ease=1.6),
            lambda: round(float(blender.mod("data").vertex_ease(E().body, bpy.context.scene).mean()), 6),
        ),
        (
            bpy.ops.ease.set_parameter,
            dict(name=name, value=0.5 * (E().design_params[0].value + E().design_params[0].min)),
            lambda: E().design_json,
        ),
        (bpy.ops.ease.load_template, dict(template=SHIRT), lambda: E().design_json),
    ]
    bpy.ops.ed.undo_push(message="start")
    for op, kw, read in steps:
        before = read()
        assert op("EXEC_DEFAULT", True, **kw) == {"FINISHED"}
        assert read() != before, op.idname()
        assert bpy.ops.ed.undo() == {"FINISHED"}
        assert read() == before, op.idname()
        assert bpy.ops.ed.redo() == {"FINISHED"}
        assert read() != before, op.idname()
    assert "UNDO" not in bpy.types.EASE_OT_save_design.bl_options  # a file only: no empty step


def test_export_greyed_out_on_an_unsaved_file(blender):
    """Export to "//ease_export" on a file never saved could be pressed and then failed."""
    bpy = blender.bpy
    blender.reset(body=True, design=TOP, pattern=True)
    s = bpy.context.scene.ease
    assert not bpy.data.filepath
    assert s.export_dir.startswith("//")  # the default: next to the .blend
    assert not bpy.ops.ease.export_pattern.poll()
    why = blender.mod("operators_base").missing(bpy.context, bpy.types.EASE_OT_export_pattern.needs)
    assert "save" in why and "Export to" in why
    s.export_dir = str(blender.tmp / "unsaved_export")
    assert bpy.ops.ease.export_pattern.poll()


def test_drape_from_a_posed_body_says_the_body_moves(blender):
    """Draping while the body was posed P1 silently put it back in A (the pattern is solved in A)."""
    bpy = blender.bpy
    blender.reset(body=True, design=TOP, pattern=True)
    s = bpy.context.scene.ease
    assert bpy.ops.ease.set_pose(pose="P1") == {"FINISHED"}
    s.drape_frames, s.drape_device = 2, "cpu"
    assert bpy.ops.ease.drape() == {"FINISHED"}
    assert s.body["ease_pose"] == "A" and s.pose == "A"
    assert "pose A" in s.drape_status and "P1" in s.drape_status


BENCH_PROBE = r"""
import importlib.util, sys
spec = importlib.util.spec_from_file_location("bench_live", sys.argv[1])
bench = importlib.util.module_from_spec(spec)
spec.loader.exec_module(bench)
bpy, live, ease_ops, data = bench._addon()
import scipy.sparse
print("RESULT", scipy.sparse.__file__, live.__file__)
"""


def test_live_bench_ignores_an_installed_copy_in_the_user_folder(tmp_path):
    """``ease bench --only live`` crashed (ModuleNotFoundError: scipy.sparse) when the Blender user
    folder held an installed extension: its bundled wheels come before this environment's packages.
    Here that folder holds a scipy without ``sparse``; the bench still gets this environment's
    scipy and the checkout's add-on."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    pytest.importorskip("bpy")
    root = Path(__file__).resolve().parent.parent
    site = (
        tmp_path
        / "user"
        / "extensions"
        / ".local"
        / "lib"
        / f"python{sys.version_info[0]}.{sys.version_info[1]}"
        / "site-packages"
        / "scipy"
    )
    site.mkdir(parents=True)
    (site / "__init__.py").write_text("# a scipy of another build, without sparse\n")
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(tmp_path / "user"), WARP_CACHE_PATH=str(root / ".cache" / "warp"))
    r = subprocess.run(
        [sys.executable, "-c", BENCH_PROBE, str(root / "benchmarks" / "bench_live.py")],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    line = next((l for l in r.stdout.splitlines() if l.startswith("RESULT ")), None)
    assert r.returncode == 0 and line, r.stdout[-2000:] + r.stderr[-2000:]
    _, sparse, live = line.split()
    assert str(tmp_path) not in sparse
    assert Path(live).resolve().is_relative_to(root)


def test_a_re_solve_moves_every_part_of_the_pieces_in_place(blender):
    """One update of the pattern objects (build.update_pattern_objects, which Live uses too): a
    re-solve of the same cut (Optimize again, Transfer) moves the pieces, their outlines, grain
    lines and labels in place: the same datablocks, no new name."""
    bpy = blender.bpy
    blender.reset(body=True, design=TOP, pattern=True)

    def datablocks():
        return {
            o.name: (o.session_uid, o.data.session_uid)
            for role in ("pattern_panel", "pattern_panel_part")
            for o in blender.objects(role)
        }

    def outline_points():
        return {
            o.name: [tuple(p.co) for sp in o.data.splines for p in sp.points][:5]
            for o in blender.objects("pattern_panel_part")
            if o.name.startswith("EASE outline")
        }

    before, pts = datablocks(), outline_points()
    assert before and any(n.startswith("EASE grain") for n in before)
    bpy.context.scene.ease.fit_size = "XL"
    assert bpy.ops.ease.transfer_size() == {"FINISHED"}
    assert datablocks() == before
    assert outline_points() != pts  # the outlines moved with the pieces
    n_curves, n_meshes = len(bpy.data.curves), len(bpy.data.meshes)
    assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
    assert datablocks() == before and (len(bpy.data.curves), len(bpy.data.meshes)) == (n_curves, n_meshes)
