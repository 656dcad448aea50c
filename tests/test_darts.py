"""Darts end to end on the real body: the design format, the slit in the cut, the legs
sewn to equal length in the pattern, the export drawing (legs, fold, drill hole,
notches in SVG, AAMA DXF and PDF), the drape welding the legs, and bad darts refused
with the field named (exit status 2 through the CLI)."""

import copy
from pathlib import Path

import numpy as np
import pytest

from core.design import load_design
from core.design.templates import TEMPLATES, template_path
from core.errors import DesignError


@pytest.fixture(scope="module")
def blouse_run(anny):
    from core import workflows as wf

    prep = wf.prepare(template_path("blouse_fitted"), body=anny)
    return prep, wf.reference(prep)


def _design(darts):
    d = TEMPLATES["blouse_fitted"]()
    d["garments"][0]["panels"][0]["darts"] = darts
    return d


def test_dart_round_trips_and_designs_without_darts_write_none():
    d = load_design(TEMPLATES["blouse_fitted"]())
    again = load_design(d.to_json())
    assert again.garments[0].panels[0].darts == d.garments[0].panels[0].darts
    assert d.to_json()["garments"][0]["panels"][0]["darts"][0]["intake"] == "auto"
    top = load_design(TEMPLATES["top_sleeveless"]()).to_json()
    assert all("darts" not in p for g in top["garments"] for p in g["panels"])


@pytest.mark.parametrize(
    "dart, field",
    [
        ({"name": "d_left", "line": "side_left", "apex": "bust_left", "intake": 0}, "darts[0].intake"),
        ({"name": "d_left", "line": "side_left", "apex": "bust_left", "intake": -0.01}, "darts[0].intake"),
        ({"name": "d_left", "line": "side_left", "apex": {"landmark": "bust_left"}}, "darts[0].apex"),
        ({"name": "d_left", "line": "side_left"}, "darts[0].apex"),
        ({"name": "d_left", "line": "side_left", "apex": "bust_left", "depth": 1}, "darts[0].depth"),
    ],
)
def test_bad_dart_fields_are_refused_on_load(dart, field):
    with pytest.raises(DesignError) as exc:
        load_design(_design([dart]))
    assert field in exc.value.path


@pytest.mark.parametrize(
    "dart, field, words",
    [
        ({"name": "d_left", "line": "side_left", "apex": "no_such_point"}, "darts[0].apex", "unknown keypoint"),
        ({"name": "d_left", "line": "no_line", "apex": "bust_left"}, "darts[0].line", "no seam or hem line"),
        # the apex on the back: the dart line leaves the front
        ({"name": "d_left", "line": "side_left", "apex": "chest_back"}, "darts[0]", "off its panel"),
    ],
)
def test_bad_dart_exits_2_naming_the_field(dart, field, words, tmp_path, capsys):
    import json

    from core.cli import main

    path = tmp_path / "bad.json"
    path.write_text(json.dumps(_design([dart])))
    assert main(["cut", str(path), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert field in err and words in err and len(err.strip().splitlines()) == 1


def test_dart_slits_the_cut_and_its_legs_sew_to_equal_length(blouse_run):
    prep, run = blouse_run
    cut, pattern = prep.cut, run.pattern
    darts = [s for s in cut.seams if s.kind == "dart"]
    assert sorted(s.name for s in darts) == [
        "blouse.bust_dart_left",
        "blouse.bust_dart_right",
        "blouse.waist_dart_left",
        "blouse.waist_dart_right",
    ]
    assert sorted(cut.darts) == sorted(s.name for s in darts)
    front = cut.panel("blouse.front")
    boundary = set(np.concatenate(front.boundary).tolist())
    for s in darts:
        assert s.panel_a == s.panel_b == "blouse.front"
        # the slit: two distinct local vertices per leg point (but the apex), on the boundary, one global id
        assert s.apex == s.verts_b[-1] and np.all(s.verts_a[:-1] != s.verts_b[:-1])
        assert set(s.verts_a.tolist()) <= boundary and set(s.verts_b.tolist()) <= boundary
        assert np.array_equal(front.vertex_ids[s.verts_a], front.vertex_ids[s.verts_b])
        # the sewn point stops short of the true apex by the apex offset (along the body)
        apex = prep.cut.positions(prep.reference)[front.vertex_ids[s.apex]]
        gap = np.linalg.norm(apex - cut.darts[s.name]["apex"])
        offset = 0.025 if "bust" in s.name else 0.02  # the template's apex offsets
        assert 0.5 * offset < gap <= offset + 2e-3
    for s in (s for s in pattern.seams if s.kind == "dart"):
        a, b = pattern.seam_polylines(s)
        la = np.linalg.norm(np.diff(a, axis=0), axis=1).sum()
        lb = np.linalg.norm(np.diff(b, axis=0), axis=1).sum()
        assert abs(la - lb) <= 1e-4, s.name  # 0.1 mm
        assert np.linalg.norm(a[0] - b[0]) > 0.01  # the dart opens in the flat pattern
        rec = pattern.report["darts"][s.name]
        assert rec["leg_difference_mm"] <= 0.1 and rec["intake_mm"] > 10
    assert run.figures["flipped"] == 0


def test_export_draws_legs_fold_drill_hole_and_notches(blouse_run, tmp_path):
    from core.export import export_pattern
    from core.export.pieces import build_pieces

    _, run = blouse_run
    pieces = {p.name: p for p in build_pieces(run.pattern)}
    front = pieces["blouse.front"]
    assert len(front.darts) == 4 and not pieces["blouse.back"].darts
    for d in front.darts:
        assert len(d.legs) == 2 and np.allclose(d.legs[0][-1], d.legs[1][-1])
        assert sum(n.seam == d.name for n in front.notches) == 2
        assert 0.005 < np.linalg.norm(d.drill - d.apex) <= 0.0101
        if "bust" in d.name:
            assert d.fold[1][1] < d.fold[0][1]  # a level (bust) dart is pressed down
    # upright (waist) darts are pressed towards the centre front: the two arrows point at each other
    waist = sorted((d for d in front.darts if "waist" in d.name), key=lambda d: d.fold[0][0])
    assert [np.sign(d.fold[1][0] - d.fold[0][0]) for d in waist] == [1.0, -1.0]
    # the outline bridges the mouth: no leg vertex but the mouths lies on it
    export_pattern(run.pattern, tmp_path, formats=("svg", "dxf", "pdf"))
    svg = (tmp_path / "pattern.svg").read_text()
    assert svg.count('class="dart"') == 4 and svg.count('class="drill"') == 4
    import ezdxf

    doc = ezdxf.readfile(tmp_path / "pattern_astm.dxf")
    ents = [e for b in doc.blocks for e in b]
    assert sum(e.dxftype() == "POINT" and e.dxf.layer == "13" for e in ents) == 4
    assert sum(e.dxf.layer == "8" for e in ents) == 4 * 4
    assert (tmp_path / "pattern_a4.pdf").stat().st_size > 0


def test_drape_welds_the_legs(blouse_run):
    from core.drape.mesh import build_cloth

    _, run = blouse_run
    cloth = build_cloth(run.pattern)
    front = run.pattern.panel("blouse.front")
    for s in (s for s in run.pattern.seams if s.kind == "dart"):
        ga, gb = front.vertex_ids[s.verts_a], front.vertex_ids[s.verts_b]
        assert np.array_equal(cloth.particle_of[ga], cloth.particle_of[gb])


@pytest.mark.slow
def test_set_intake_is_held(anny):
    from core import workflows as wf

    d = TEMPLATES["blouse_fitted"]()
    # the bust darts alone, set: the template's waist darts (set at 20 mm) are held the same way, and
    # converging on the bust point beside them the set bust darts' legs end 0.6 mm apart
    front = d["garments"][0]["panels"][0]
    front["darts"] = [dict(front["darts"][0], intake=0.04)]
    run = wf.reference(wf.prepare(d, body=anny))
    assert sorted(run.pattern.report["darts"]) == ["blouse.bust_dart_left", "blouse.bust_dart_right"]
    for rec in run.pattern.report["darts"].values():
        assert rec["intake_set_mm"] == 40.0
        # 0.51 mm with the solver's gap step between the legs (issue 30), 0.5 before it
        assert abs(rec["intake_mm"] - 40.0) <= 2.0 and rec["leg_difference_mm"] <= 0.6


def test_skirt_back_darts_open_and_export(anny, tmp_path):
    from core import workflows as wf
    from core.export import export_pattern

    run = wf.reference(wf.prepare(template_path("skirt_darted"), body=anny))
    darts = run.pattern.report["darts"]
    assert sorted(darts) == ["skirt.back_dart_left", "skirt.back_dart_right"]
    assert all(r["intake_mm"] > 10 and r["leg_difference_mm"] <= 0.1 for r in darts.values())
    export_pattern(run.pattern, tmp_path, formats=("svg",))
    assert (tmp_path / "pattern.svg").read_text().count('class="dart"') == 2


@pytest.mark.parametrize("place, length", [(0.5953, 0.1467), (0.6, 0.16), (0.6, 0.18)])
def test_skirt_back_dart_starts_on_the_waist_seam_across_its_range(anny, place, length):
    """Inside the darted skirt's declared ranges (0.5953 / 0.1467: the range test's interior7)
    the back dart's mouth is on the waist ring, not on the resolver geodesic's joint 5.3 mm
    above it (from where the waist seam dropped to the ring point along the dart: "cut lines
    'skirt.back_dart_left' and 'skirt.waist' cross"), and each dart is one seam of the back."""
    from core.cut import cut_design
    from core.design.resolve import Resolver, instance_vertices, resolve

    d = TEMPLATES["skirt_darted"]()
    d["parameters"]["back_dart_place"]["value"] = place
    d["parameters"]["back_dart_length"]["value"] = length
    d = load_design(d)
    d.refine_edge_length = None
    R = Resolver(d, anny, instance_vertices(d, anny))
    lines = {l.name: l for l in resolve(d, anny, resolver=R).lines}
    ring_z = R.position(R.point("waist_front", "test"))[2]
    for side in ("left", "right"):
        mouth = R.position(lines[f"skirt.back_dart_{side}"].points[0])
        assert abs(mouth[2] - ring_z) < 1e-3, (side, mouth[2] - ring_z)
    cut = cut_design(d, body=anny)
    assert sorted(cut.darts) == ["skirt.back_dart_left", "skirt.back_dart_right"]
    assert all(r["panel"] == "skirt.back" for r in cut.darts.values())


def test_mirrored_neckline_darts_from_one_mouth_touch_only_there(anny):
    """On men:XXL the four-dart blouse's neckline darts both start at the neckline's centre front
    and pass 0.4-0.5 mm from the sternum's midline vertex 1.5 mm below it. The tracer snapped the
    left dart to that vertex, the mirrored right half then passed it too, and the cut refused the
    dart ("it gives 2 stretches"). A mirrored dart never snaps to the midline
    (core.cut.darts.midline_guards): each dart is one seam, the two meet only at their mouth."""
    from core.cut import cut_design

    d = load_design(TEMPLATES["blouse_four_darts"]())
    d.refine_edge_length = None
    cut = cut_design(d, body=anny, shape="men:XXL")
    panel = next(p for p in cut.panels if p.name == "blouse.front")
    by_name = {s.name: s for s in cut.seams}
    ids = {}
    for side in ("left", "right"):
        name = f"blouse.neck_dart_{side}"
        assert name in cut.darts and name in by_name, sorted(by_name)
        s = by_name[name]
        ids[side] = (set(panel.vertex_ids[s.verts_a[1:]]) | set(panel.vertex_ids[s.verts_b[1:]]), s)
    mouth_l, mouth_r = (ids[k][1] for k in ("left", "right"))
    assert mouth_l.verts_a[0] != mouth_l.verts_b[0] and mouth_r.verts_a[0] != mouth_r.verts_b[0]
    assert not ids["left"][0] & ids["right"][0]


def test_auto_darts_are_placed_written_back_and_reduce_the_error(anny, blouse_run):
    from core import workflows as wf
    from core.cut.auto_darts import place_darts
    from core.design import save_design

    d = TEMPLATES["blouse_fitted"]()
    d["garments"][0]["panels"][0]["darts"] = {"auto": {"max_count": 1, "max_intake": 0.08}}
    design = load_design(d)
    assert design.garments[0].panels[0].auto_darts == {"max_count": 1, "max_intake": 0.08}
    placed = place_darts(design, body=anny)
    darts = placed.garments[0].panels[0].darts
    assert len(darts) == 1 and darts[0].apex == "bust_left" and placed.garments[0].panels[0].auto_darts is None
    # written back: the placed design saves and loads as an ordinary design with that dart
    import pathlib
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        again = load_design(save_design(placed, pathlib.Path(tmp) / "placed.json"))
    assert again.garments[0].panels[0].darts == darts
    with_darts = wf.reference(wf.prepare(placed, body=anny)).figures["compliance mean %"]
    plain = copy.deepcopy(TEMPLATES["blouse_fitted"]())
    plain["garments"][0]["panels"][0].pop("darts")
    without = wf.reference(wf.prepare(plain, body=anny)).figures["compliance mean %"]
    assert with_darts < without - 0.2


def test_auto_darts_on_sided_panels_mirror_without_a_name_clash(anny):
    """Issue 30: ``"darts": "auto"`` on the pants (and a shirt's sleeves) was refused: a sided panel's dart
    ``front_left_auto_dart_1_left`` got a ``*_right`` twin in its own panel and another in the mirror
    panel (``... the name is taken by a line``). Now a sided panel's automatic darts carry the side in
    the panel's name, and its mirror panel alone gets their counterparts."""
    from core.cut import cut_design
    from core.cut.auto_darts import place_darts

    d = TEMPLATES["pants"]()
    for p in d["garments"][0]["panels"]:
        p["darts"] = "auto"
    placed = place_darts(load_design(d), body=anny)
    names = sorted(dd.name for p in placed.garments[0].panels for dd in p.darts)
    assert names and all(n.startswith(("front_left_auto_dart_", "back_left_auto_dart_")) for n in names), names
    cut = cut_design(placed, body=anny)
    mirrored = {n.replace("_left_", "_right_", 1) for n in names}
    assert sorted(cut.darts) == sorted(f"pants.{n}" for n in set(names) | mirrored)
    for name, rec in cut.darts.items():
        assert rec["panel"] == "pants." + ("front" if ".front" in name else "back") + (
            "_left" if "_left_" in name else "_right"
        ), name


def test_auto_darts_skip_an_apex_too_near_every_line():
    """A curvature peak whose nearest line would leave a dart under the cut's least length is opened
    from the next line, or left to the flattening: the skirt's front peak 35 mm above the hem was
    refused (``a dart needs 20 mm after the apex offset``)."""
    import numpy as np

    from core.cut.auto_darts import APEX_OFFSET, MIN_LENGTH, _mouth_line

    t = np.linspace(0.0, 1.0, 11)[:, None]
    hem = np.hstack([t * 0.2, np.zeros_like(t), np.zeros_like(t)])
    side = np.hstack([np.full_like(t, 0.2), np.zeros_like(t), t * 0.3])
    lines = [("hem", hem, np.ones(len(t), bool)), ("side", side, np.ones(len(t), bool))]
    near_hem = np.array([0.05, 0.0, APEX_OFFSET + MIN_LENGTH - 0.005])
    assert _mouth_line(lines, near_hem)[0] == "side"
    far = np.array([0.06, 0.0, 0.1])  # above a point of the hem
    name, length = _mouth_line(lines, far)
    assert name == "hem" and abs(length - (0.1 - APEX_OFFSET)) < 1e-12
    # the nearest point off the panel (along another piece): not this line
    lines[0] = ("hem", hem, np.zeros(len(t), bool))
    assert _mouth_line(lines, far)[0] == "side"
    assert _mouth_line([lines[0]], far) is None


def test_auto_darts_request_is_checked():
    for bad, field in (
        ({"auto": {"max_count": 0}}, "max_count"),
        ({"auto": {"max_intake": -1}}, "max_intake"),
        ({"auto": {"count": 2}}, "count"),
        ({"manual": 1}, "darts"),
    ):
        with pytest.raises(DesignError) as exc:
            load_design(_design(bad))
        assert field in exc.value.path


def test_cut_and_pattern_files_keep_the_darts(blouse_run, tmp_path):
    from core.cut.io import load_cut, save_cut
    from core.pattern.io import load_pattern, save_pattern

    prep, run = blouse_run
    save_cut(prep.cut, tmp_path / "cut")
    cut = load_cut(tmp_path / "cut")
    assert sorted(cut.darts) == sorted(prep.cut.darts)
    rec, again = prep.cut.darts["blouse.bust_dart_left"], cut.darts["blouse.bust_dart_left"]
    assert again["intake"] is None and np.allclose(again["apex"], rec["apex"])
    assert [s.kind for s in cut.seams] == [s.kind for s in prep.cut.seams]
    pattern = load_pattern(save_pattern(run.pattern, tmp_path / "p"))
    assert [s.apex for s in pattern.seams] == [s.apex for s in run.pattern.seams]


# ----------------------------------------------------------------------------- darts that grade


@pytest.fixture(scope="module")
def four_darts(anny):
    """The four-dart blouse on women:M (its fitted reference) and the body instances of other sizes."""
    from core import workflows as wf
    from core.body.instance import body_instance, instance_shape

    prep = wf.prepare(TEMPLATES["blouse_four_darts"](), body=anny)
    solver = wf.make_solver(prep)
    ref = wf.reference(prep, solver=solver).pattern
    pose = prep.cut.body.get("pose")
    bodies = {s: body_instance(anny, instance_shape(anny, f"women:{s}"), pose) for s in ("XS", "S", "L")}
    return prep, solver, ref, bodies


def _cup(X, faces, landmark, near):
    """Where the bust landmark's rule (most anterior vertex) lies within 5 cm of ``near``."""
    ids = np.flatnonzero(np.linalg.norm(X - near, axis=1) < 0.05)
    return X[ids[np.argmin(X[ids, 1])]]


def test_a_darts_apex_follows_the_cup_onto_another_body(four_darts, anny):
    """On women:L the bust point the cut's embedding carries from M lies 30 mm medial of L's most anterior
    bust vertex (the landmark's own rule); the darts' sewn points move with the cloth around them to end
    their apex offset from the latter. Both legs of every dart stay on one body point; XS (whose cup is the
    carried point) keeps the embedding's positions; the other panels do not move."""
    from core.cut.darts import follow_cups

    prep, _, _, bodies = four_darts
    cut, faces = prep.cut, np.asarray(anny.faces)
    for size, X in bodies.items():
        plain, moved = cut.positions(X), follow_cups(cut, prep.reference, X)
        back = cut.panel("blouse.back").vertex_ids
        assert np.array_equal(moved[back], plain[back])
        for s in cut.seams:
            if s.kind != "dart":
                continue
            ids = cut.panel(s.panel_a).vertex_ids
            assert np.abs(moved[ids[s.verts_a]] - moved[ids[s.verts_b]]).max() < 1e-12, (size, s.name)
        if size == "XS":
            assert np.array_equal(moved, plain)
            continue
        for side in ("left", "right"):
            carried = anny.landmarks[f"bust_{side}"].position(X, faces)
            cup = _cup(X, faces, f"bust_{side}", carried)
            tips = [
                cut.panel(s.panel_a).vertex_ids[s.apex]
                for s in cut.seams
                if s.kind == "dart" and s.name.endswith(f"_dart_{side}")
            ]
            assert len(tips) == 4
            now = np.linalg.norm(moved[tips] - cup, axis=1)
            before = np.linalg.norm(plain[tips] - cup, axis=1)
            # measured: the sewn points end their apex offset from the cup on S (5 mm, the neckline dart 7.5 mm;
            # 9-16 mm with the embedding's points, its cup 12 mm from the carried point), 2.7-5.2 mm past it on L
            # (22-30 mm: the move is capped where the map would not stay one-to-one)
            offset = np.array(
                [
                    cut.darts[s.name]["apex_offset"]
                    for s in cut.seams
                    if s.kind == "dart" and s.name.endswith(f"_dart_{side}")
                ]
            )
            past, was = now - offset, before - offset
            assert past.max() < 0.006 and past.max() < 0.6 * was.min(), (size, side, now, before)


def test_four_darts_graded_to_s_holds_every_target(four_darts):
    """Issue 30's targets on women:S (the reference on M transferred): with the apexes following the cup
    the front piece's shear p95 is 5.7 deg and warp 2.86 % (7.5 deg and 3.01 % with the darts where
    the embedding carried them)."""
    from benchmarks.measure_darts import TARGETS, four_dart_figures, missed

    prep, solver, ref, _ = four_darts
    from core import workflows as wf

    fig = four_dart_figures(wf.transfer(prep, "S", solver=solver, start=ref).pattern, prep.body)
    assert not missed(fig), (fig, TARGETS)


def test_four_darts_graded_to_xs_on_a_solver_made_there_holds_every_target(four_darts, monkeypatch):
    """Issue 30's targets on women:XS: with the solver made on M the front piece's shear p95 reads 6.5 deg (over
    6); made on XS (``transfer_solver`` ``"target"``: flattened and factorised there) 5.5 deg, bust region 1.04 %
    (1.30). A transfer that is not refused sews its darts' legs equal once: the state its refusal was weighed
    on is the result's (PatternSolver.refusal)."""
    from benchmarks.measure_darts import TARGETS, four_dart_figures, missed
    from core import workflows as wf
    from core.pattern.optimizer.solver import PatternSolver

    prep, solver, ref, _ = four_darts
    sewn = []
    sew = PatternSolver.legs_sewn_equal
    monkeypatch.setattr(PatternSolver, "legs_sewn_equal", lambda self, state: sewn.append(state) or sew(self, state))
    run = wf.transfer(prep, "XS", solver=solver, start=ref, transfer_solver="target")
    assert len(sewn) == 1
    fig = four_dart_figures(run.pattern, prep.body)
    assert not missed(fig), (fig, TARGETS)
    assert fig["front shear p95 deg"] < 6.0 and fig["bust region %"] < 1.2, fig


def test_four_darts_graded_to_l_follows_the_bigger_cup(four_darts):
    """Measured (women:M -> L, fitted): bust region 3.22 -> 2.24 %, front shear p95 16.5 -> 9.9 deg, legs
    0.41 -> 0.11 mm with the apexes following the cup; issue 30 asks the bust region within M's + 0.5 point
    (1.80 %): see the next test."""
    from benchmarks.measure_darts import four_dart_figures

    prep, solver, ref, _ = four_darts
    from benchmarks.measure_darts import _target_spec
    from core import workflows as wf

    run = wf.transfer(prep, "L", solver=solver, start=ref)
    # the per-size bench records the target body as ease transfer does (its bust region on L's landmarks)
    pose = prep.cut.body.get("pose")
    assert run.pattern.body == _target_spec(prep.cut, prep.body, run.pattern.body["shape"], pose, "women:L")
    fig = four_dart_figures(run.pattern, prep.body)
    assert fig["crossings"] == 0 and fig["flipped"] == 0 and fig["collapsed"] == 0
    assert fig["bust region %"] < 2.5 and fig["front shear p95 deg"] < 11.0 and fig["legs mm"] < 0.3, fig


def test_four_darts_graded_to_l_keeps_the_bust_region_of_m(four_darts):
    """Issue 30: women:M -> L keeps the bust region within M's figure + 0.5 point. Measured: M 1.32 %, L 1.60 %
    with the template's cup rule (the darts re-drafted on L's cup, ending at their apex offsets from its bust
    point); 1.83 % with the sewn points where the cup's move leaves them (7.7-12.7 mm from the cup), 2.19 %
    on M's solver (docs/darts.md, "Graded to L")."""
    from benchmarks.measure_darts import four_dart_figures

    prep, solver, ref, _ = four_darts
    from core import workflows as wf

    m = four_dart_figures(ref, prep.body)["bust region %"]
    fig = four_dart_figures(wf.transfer(prep, "L", solver=solver, start=ref).pattern, prep.body)
    assert fig["crossings"] == 0 and fig["flipped"] == 0 and fig["collapsed"] == 0, fig
    assert fig["bust region %"] <= m + 0.5, (m, fig)


def test_regraded_darts_end_at_their_apex_offsets_from_the_cup(four_darts, anny):
    """``follow_cups(..., at_offsets=True)`` (the cup rule's regrade) ends every dart towards a bust point its
    apex offset from the target's cup (women:L, measured: 4.5-5.3 mm for the 5 mm darts, 8.1 mm for the
    neckline dart's 7.5), where the move alone leaves them 2.7-5.2 mm further; the back panel and the legs'
    shared body points are kept."""
    from core.cut.darts import follow_cups

    prep, _, _, bodies = four_darts
    cut, faces, X = prep.cut, np.asarray(anny.faces), bodies["L"]
    plain, drafted = follow_cups(cut, prep.reference, X), follow_cups(cut, prep.reference, X, at_offsets=True)
    back = cut.panel("blouse.back").vertex_ids
    assert np.array_equal(drafted[back], plain[back])
    for side in ("left", "right"):
        cup = _cup(X, faces, f"bust_{side}", anny.landmarks[f"bust_{side}"].position(X, faces))
        darts = [s for s in cut.seams if s.kind == "dart" and s.name.endswith(f"_dart_{side}")]
        tips = [cut.panel(s.panel_a).vertex_ids[s.apex] for s in darts]
        offset = np.array([cut.darts[s.name]["apex_offset"] for s in darts])
        for s in darts:
            ids = cut.panel(s.panel_a).vertex_ids
            assert np.abs(drafted[ids[s.verts_a]] - drafted[ids[s.verts_b]]).max() < 1e-12, s.name
        now = np.linalg.norm(drafted[tips] - cup, axis=1) - offset
        before = np.linalg.norm(plain[tips] - cup, axis=1) - offset
        assert np.abs(now).max() < 0.001 and before.min() > 0.002, (side, now, before)


def test_the_cup_rule_regrades_bigger_cups_only(four_darts):
    """``transfer_solver`` ``"cup"`` re-drafts the darts only where the target's cups are bigger than the
    design's (women's chart: L and XL, not XS or S, :func:`core.cut.darts.bigger_cups`); on S the transfer
    is the reference solver's, bit for bit; on L it reads bust region 1.60 % (reference solver 2.19)."""
    from benchmarks.measure_darts import four_dart_figures
    from core import workflows as wf
    from core.cut.darts import bigger_cups

    prep, solver, ref, bodies = four_darts
    assert [bigger_cups(prep.cut, prep.reference, bodies[s]) for s in ("XS", "S", "L")] == [False, False, True]
    assert not bigger_cups(prep.cut, prep.reference, prep.reference)
    cup, plain = (wf.transfer(prep, "S", solver=solver, start=ref, transfer_solver=t) for t in ("cup", "reference"))
    assert cup.pattern.report["darts_regraded"] is False and "darts_regraded" not in plain.pattern.report
    for a, b in zip(cup.pattern.panels, plain.pattern.panels):
        assert np.array_equal(a.uv, b.uv)
    run = wf.transfer(prep, "L", solver=solver, start=ref, transfer_solver="cup")
    assert run.pattern.report["darts_regraded"] is True
    fig = four_dart_figures(run.pattern, prep.body)
    assert fig["crossings"] == 0 and fig["flipped"] == 0 and fig["legs mm"] <= 0.1 and fig["weft %"] <= 1.0, fig
    assert fig["bust region %"] < 1.75, fig


def test_a_cup_regrade_that_does_not_solve_grades_the_designs_own_darts(four_darts, monkeypatch):
    """A bigger cup whose re-drafted darts are refused (men:XL's chest diverged so) is graded as the reference
    solver grades it, and the report says why, rather than refusing the size."""
    from core import workflows as wf
    from core.errors import PatternError
    from core.pattern import solve
    from core.pattern.optimizer.solver import PatternSolver

    prep, solver, ref, _ = four_darts
    real = PatternSolver.__init__

    def refuse_on_another_body(self, *args, flatten_on=None, **kwargs):
        if flatten_on is not None:
            raise PatternError("panel 'blouse.front': the solve diverged (a test's refusal)")
        real(self, *args, **kwargs)

    monkeypatch.setattr(solve.PatternSolver, "__init__", refuse_on_another_body)
    cup = wf.transfer(prep, "L", solver=solver, start=ref, transfer_solver="cup").pattern
    monkeypatch.undo()
    plain = wf.transfer(prep, "L", solver=solver, start=ref, transfer_solver="reference").pattern
    assert cup.report["darts_regraded"] is False
    assert "a test's refusal" in cup.report["darts_regrade_refused"]
    for a, b in zip(cup.panels, plain.panels):
        assert np.array_equal(a.uv, b.uv)


def test_bust_breakdown_splits_the_bust_region_and_the_fronts_warp(four_darts):
    """benchmarks.measure_darts.bust_breakdown (docs/darts.md, "Graded to L"): its bands by distance from the
    sewn point and from the dart legs each cover the bust region once (areas sum to 100 %, contributions to
    its mean, which is the region report's ``bust_left``); its zones cover the front piece once (their warp
    contributions sum to the piece's mean |warp|); on M the template's landmark is the cup."""
    from benchmarks.measure_darts import bust_breakdown
    from core.metrics.regions import body_landmarks, region_compliance
    from core.metrics.strains import panel_strain

    prep, _, ref, _ = four_darts
    b = bust_breakdown(ref, prep.body)
    region = region_compliance(ref, body_landmarks(ref, prep.body), names=("bust_left",))["bust_left"]
    assert b["region"]["mean"] == pytest.approx(region["mean"], abs=0.006)
    for split in ("by_apex", "by_leg"):
        rows = np.array(list(b["region"][split].values()))
        assert rows[:, 0].sum() == pytest.approx(100.0, abs=0.3)
        assert rows[:, 2].sum() == pytest.approx(region["mean"], abs=0.03)
    front = next(p for p in ref.panels if p.name == "blouse.front")
    st = panel_strain(front)
    warp = np.abs(st.warp - front.target_warp) / front.target_warp * 100.0
    zones = np.array(list(b["front"].values()))
    assert zones[:, 0].sum() == pytest.approx(100.0, abs=0.3)
    assert zones[:, 2].sum() == pytest.approx(float((warp * st.area).sum() / st.area.sum()), abs=0.03)
    assert zones[:, 4].sum() == pytest.approx(100.0, abs=0.3)
    assert b["cup_offset_mm"] == 0.0


def test_a_solve_whose_dart_legs_cross_runs_rounds_more(blouse_run, monkeypatch):
    """A solve that ends its planned iterations with a dart's legs crossed (a pattern refused for it) runs
    collapse-guard rounds more, as many again as planned at most (PatternSolver.extra_iterations). Before
    the charts' refit of 2026-12-07 blouse_fitted at one interior point of its ranges
    (tests/test_template_ranges.py's interior5) ended its 20 iterations with each waist dart's leg hooked
    past the apex (2 crossings) and was refused; 30 iterations cleared it."""
    from core.pattern.optimizer import solver as S
    from core.pattern.optimizer.guard import COLLAPSE_ROUNDS

    prep, _ = blouse_run
    solver = S.PatternSolver(prep.cut, prep.reference)
    K, cw, cg = solver.targets_reference()
    state = solver.begin(K, cw, cg)
    solver.iterate(state, state.planned)
    # the collapse guard's own rounds and rescue out of the way: only the crossing rule asks
    monkeypatch.setattr(solver, "collapsing", lambda st: False)
    monkeypatch.setattr(S, "refused", lambda st: False)
    assert not solver.gaps.crossed(state.U) and solver.extra_iterations(state) == 0
    legs = solver.gaps.legs
    k = np.flatnonzero(legs.prev_a == legs.a)[0] + 1  # a dart's second pair from its mouth
    state.U[[legs.a[k], legs.b[k]]] = state.U[[legs.b[k], legs.a[k]]]  # swapped: its legs cross
    assert solver.gaps.crossed(state.U)
    assert solver.extra_iterations(state) == COLLAPSE_ROUNDS
    state.iteration = 2 * state.planned - 1
    assert solver.extra_iterations(state) == COLLAPSE_ROUNDS
    state.iteration = 2 * state.planned  # as many again as planned: no more
    assert solver.extra_iterations(state) == 0


def test_a_solve_ends_with_its_dart_legs_sewn_equal(blouse_run):
    """A solve stopped with its darts' legs of different lengths (here after 10 iterations) gives a pattern
    whose legs are sewn equal (PatternSolver.result: dart_gaps.equal_legs, the smallest move in the system
    matrix's norm), flip-free and uncrossed; the solve's own iterate is left as it is, so a solve that goes
    on goes on from it; legs already within the tolerance give the iterate itself (the same bits)."""
    from core.pattern.optimizer import solver as S
    from core.pattern.optimizer.dart_gaps import LEG_TARGET, LEG_TOLERANCE, leg_differences

    prep, run = blouse_run
    solver = S.PatternSolver(prep.cut, prep.reference)
    K, cw, cg = solver.targets_reference()
    state = solver.begin(K, cw, cg)
    solver.iterate(state, 10)
    legs = solver.gaps.legs
    before = state.U.copy()
    apart = np.abs(leg_differences(legs, before)).max()
    assert apart > 0.1e-3  # unequal after 10 iterations (0.89 mm)
    equal = solver.legs_sewn_equal(state)
    assert equal is not state and np.array_equal(state.U, before)
    assert np.abs(leg_differences(legs, equal.U)).max() <= LEG_TARGET
    assert not solver.gaps.crossed(equal.U)
    moved = np.linalg.norm(equal.U - before, axis=1)
    assert 0 < moved.max() < apart  # a correction of the legs, not a new solve (0.44 mm)
    uv = solver.result(state).uv
    assert all(np.array_equal(uv[pd.name], equal.U[pd.offset : pd.offset + pd.n]) for pd in solver.panels)
    assert solver.legs_sewn_equal(equal) is equal  # within the tolerance: untouched
    # the written pattern's own figure (build.dart_report), on the reference's full solve
    assert all(r["leg_difference_mm"] <= 1000 * LEG_TOLERANCE for r in run.pattern.report["darts"].values())


def test_the_per_size_table_is_written_into_the_bench_results(tmp_path):
    """benchmarks.measure_darts.write_sizes (``--sizes --into``) replaces the pattern bench's per-size table and
    its entry in pattern.json, and nothing else; written again, its note is replaced, not repeated."""
    import json
    import shutil

    from benchmarks.measure_darts import write_sizes

    src = Path(__file__).resolve().parents[1] / "benchmarks" / "results"
    for name in ("pattern.json", "pattern.md"):
        shutil.copy(src / name, tmp_path / name)
    before = (tmp_path / "pattern.md").read_text().split("\n")
    rows = json.loads((tmp_path / "pattern.json").read_text())["four_darts_sizes"]
    rows["XS @ 1.1"]["fitted"]["bust region %"] = 9.87
    for note in ("first note", "second note"):
        write_sizes(tmp_path, rows, note)
    after = (tmp_path / "pattern.md").read_text().split("\n")
    changed = [line for line in after if line not in before]
    assert len(changed) == 2 and "| 9.87 |" in changed[0] and changed[1] == "second note", changed
    removed = [line for line in before if line not in after]  # the row, and the note of the last rerun if any
    assert removed[0] == next(line for line in before if line.startswith("| XS @ 1.1 | fitted"))
    assert all(line.startswith("This table alone rerun") for line in removed[1:]), removed
    data = json.loads((tmp_path / "pattern.json").read_text())
    assert data["four_darts_sizes"]["XS @ 1.1"]["fitted"]["bust region %"] == 9.87
    assert data["four_darts_sizes_note"] == "second note"


def _tip_legs(last_a, last_b):
    """A dart's legs (a: 0-3, b: 4-7, apex 8) as skirt_darted's back dart read on women:XL before the tip's
    axis (mm, the apex at 0): the last pair ``last_a`` / ``last_b`` 0.6 mm from the apex."""
    from core.pattern.optimizer.dart_gaps import MIN_OPENING, DartLegs

    a = [(0.58, 28.79), (-0.56, 17.47), (-0.73, 5.97), last_a]
    b = [(-4.72, 28.47), (-2.27, 17.37), (-0.83, 5.92), last_b]
    U = 1e-3 * np.array([*a, *b, (0.0, 0.0)])
    i = np.arange(4)
    prev, nxt = np.maximum(i - 1, 0), np.r_[i[1:], 8]
    dist = np.linalg.norm(U[:4], axis=1)
    legs = DartLegs(i, i + 4, prev, prev + 4, nxt, np.r_[nxt[:3] + 4, 8], MIN_OPENING * dist, 0.005)
    return legs, U


def test_the_pair_next_to_the_apex_reads_the_tip_wedge():
    """The pair next to the apex is measured across the line from it to the apex: skirt_darted's back darts
    transferred to women:XL ended with that pair 0.6 mm from the apex, off the axis from the pair before, the
    legs swapped there (one leg's last edge across the other leg: refused, 1 crossing a dart). Read across the
    axis through the pair before, its gap was positive, so the solver neither opened it nor saw a crossing
    (the edges ending at the apex were left out of its check); in a wedge that opens to the apex it is apart."""
    from core.pattern.optimizer.dart_gaps import GapCorrection, leg_gaps

    legs, U = _tip_legs((0.38, 0.60), (0.38, 0.57))
    assert leg_gaps(legs, U)[-1] < 0 and leg_gaps(legs, U)[:3].min() > 0
    assert GapCorrection(legs).crossed(U)
    legs, U = _tip_legs((0.05, 0.60), (-0.05, 0.60))
    assert leg_gaps(legs, U).min() > 0 and not GapCorrection(legs).crossed(U)


def test_skirt_darted_transfers_to_xl_with_no_crossing(anny):
    """skirt_darted (women:M) transferred to XL: refused before (the legs of each back dart crossed once near
    the seat point, test above); now cut with its legs apart up to the apex."""
    from core import workflows as wf
    from core.metrics.injectivity import crossings, dart_gaps

    prep = wf.prepare(template_path("skirt_darted"), body=anny)
    solver = wf.make_solver(prep)
    ref = wf.reference(prep, solver=solver)
    run = wf.transfer(prep, "XL", solver=solver, start=ref.pattern)
    assert all(c["count"] == 0 for c in crossings(run.pattern).values())
    gaps = dart_gaps(run.pattern)
    assert sorted(gaps) == ["skirt.back_dart_left", "skirt.back_dart_right"]
    assert all(g["crossings"] == 0 and g["min_gap_mm"] > 0 for g in gaps.values())
