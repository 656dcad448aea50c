"""The designer walk: a seeded random sequence of what a designer does, driven only through the
add-on's operators and properties, with the scene checked after every step (issue 32).

Steps: add the body (every chart and size), load templates, move keypoints, set parameters in and
out of range, paint (attribute writes, as a stroke leaves them) with X-mirror on and off, Live on
and off and its ticks, undo and redo, optimize, transfer, adapt, drape (a few frames), export;
with ``--full`` also marker (one second of nesting) and a tiny render (5 %, one sample).

After every step:

- no operator met a bug (``state.BUGS``: an exception that is no user error) and no step raised;
- the panels say what the scene holds: phenotype sliders = the body's shape, chart and size = the
  body's size record (and its shape is that size's), the pose, the measurements shown = the body's,
  the parameter sliders = the design's, the ease panel one of the cut's, the sizes on the charts;
- no object or datablock name ends in ``.001``;
- an operator that cannot run is greyed out with its reason;
- when Live says "converged", the stored pattern is the cold solve of the current paint.

Headless there is no hypothesis in the environment: the walk is a seeded random walk. CI runs the
seeds of :data:`CI_SEEDS` (:data:`CI_STEPS` steps each); ``pytest --full`` runs
:data:`FULL_SEEDS` walks of :data:`FULL_STEPS` steps (the designer's afternoon), every template.
The threaded walks (:data:`THREADED_CI_SEEDS`, :data:`THREADED_FULL_SEEDS`) run Live's build and
solve in worker threads, as Blender's window does, and let them land (the jobs' poll) before half
of the checks; the operators are still called as a script calls them (EXEC_DEFAULT), so Apply
Size/Pose, Load, Optimize, Transfer, Adapt and Drape compute in line there (threaded paths are
tested on their own: Optimize in test_addon_pattern, whose job Transfer and Adapt share untested,
Apply Size/Pose in test_addon_body, Load in test_addon_design, Drape in test_addon_drape).
"""

from __future__ import annotations

import os
import random
import re

import numpy as np
import pytest

# the CI seeds are walks that found bugs: a restart from a pattern of another cut (2), a segfault
# on undo after Live rebuilt the pieces and "converged" over a re-cut's pattern (4), "converged"
# restored by an undo (8)
CI_SEEDS, CI_STEPS = (2, 4, 8), 40
# walks with the jobs threaded as in Blender's window (Live's build and solve in workers, landing
# on the jobs' poll between the designer's moves); the CI seed and the --full ones
THREADED_CI_SEEDS, THREADED_FULL_SEEDS = (21,), tuple(range(30, 35))
FULL_SEEDS, FULL_STEPS = tuple(range(10, 20)), 500
CHEAP = ("top_sleeveless.json", "blouse_fitted.json")  # two-panel designs: CI's templates
POSES = ("A", "T", "P1", "P2", "P3")
MEASURE_TOL_CM = 0.05
TRACE = bool(os.environ.get("EASE_WALK_TRACE"))  # each move printed as it starts (a crash's last)


class Walk:
    """The designer's moves on the session's scene (:class:`conftest.AddonScene`) and the checks."""

    def __init__(self, blender, rng: random.Random, full: bool):
        self.b, self.rng, self.full = blender, rng, full
        self.bpy = blender.bpy
        self.templates = (
            sorted(p.name for p in blender.mod("data").template_dir().glob("*.json")) if full else list(CHEAP)
        )
        self.log = []
        self.results = []  # (operator, FINISHED / ERROR / GREYED / CANCELLED)
        self.undo_ready = False  # an undo step was pushed since the last file read

    # -- scene access (after an undo, references taken before dangle: always fetch afresh)
    @property
    def s(self):
        return self.bpy.context.scene.ease

    def mod(self, name):
        return self.b.mod(name)

    def op(self, opname, *args, **kw):
        """Run ``bpy.ops.ease.<name>`` as a button press (with its undo push); its result set, or
        ``{"ERROR": message}`` (a refusal: greyed out, or a user error reported)."""
        op = getattr(self.bpy.ops.ease, opname)
        if not op.poll():
            why = self.mod("operators_base").missing(
                self.bpy.context, getattr(getattr(self.bpy.types, op.idname()), "needs", ())
            )
            assert why, f"{opname} greyed out without a reason"
            self.results.append((opname, "GREYED"))
            return {"GREYED": why}
        try:
            out = op("EXEC_DEFAULT", True, *args, **kw)
        except RuntimeError as exc:  # the operator reported an error (a user's, or a bug: checked)
            out = {"ERROR": str(exc)}
        self.undo_ready = True
        self.results.append((opname, sorted(out)[0]))
        return out

    def edited(self, what: str):
        """A property was edited in the panel: the UI pushes an undo step after its update."""
        self.bpy.ops.ed.undo_push(message=what)
        self.undo_ready = True

    # -- moves ------------------------------------------------------------------------------
    def add_body(self):
        self.op("add_body", source="DEFAULT")

    def set_size(self):
        from core.body.sizes import CHARTS

        chart = self.rng.choice(sorted(CHARTS))
        self.s.chart = chart
        self.edited("chart")
        self.s.size = self.rng.choice(self.mod("data").chart_sizes(chart))
        self.edited("size")
        self.op("set_size")

    def set_pose(self):
        self.op("set_pose", pose=self.rng.choice(POSES))

    def load_template(self):
        self.op("load_template", template=self.rng.choice(self.templates))

    def move_keypoint(self):
        s = self.s
        if s.body is None or not s.design_json:
            return self.op("assign_keypoint", name="x", vertex=0)
        kps = self.mod("convert").read_keypoints(s.body.data)
        if not kps:
            return
        name = self.rng.choice(sorted(kps))
        tri, _ = kps[name]
        faces = self.mod("convert").get_triangles(s.body.data)
        # a neighbouring vertex: the keypoint moves a little, as a designer nudges it
        ring = np.flatnonzero((faces == faces[tri][self.rng.randrange(3)]).any(axis=1))
        vertex = int(faces[self.rng.choice(list(ring))][self.rng.randrange(3)])
        self.op("assign_keypoint", name=name, vertex=vertex)

    def set_parameter(self):
        s = self.s
        if not s.design_params:
            return
        item = s.design_params[self.rng.randrange(len(s.design_params))]
        lo, hi = item.min, item.max
        if lo < -1e8 or hi > 1e8:
            lo, hi = item.value * 0.8, item.value * 1.2
        inside = self.rng.random() < 0.7
        value = self.rng.uniform(lo, hi) if inside else hi + self.rng.uniform(0.01, 0.5)
        if self.rng.random() < 0.5:
            item.value = value  # the slider (live re-cut)
            self.edited("parameter")
        else:
            self.op("set_parameter", name=item.name, value=value)

    def paint(self):
        s = self.s
        if s.body is None:
            return
        obj = s.body
        me = obj.data
        if self.rng.random() < 0.3:
            me.use_mirror_x = not me.use_mirror_x
            self.edited("X-mirror")
        if me.color_attributes.get("ease") is None:
            return
        data, ramp = self.mod("data"), self.mod("ramp")
        verts = self.b.verts(obj).astype(np.float64)
        centre = verts[self.rng.randrange(len(verts))]
        patch = np.linalg.norm(verts - centre, axis=1) < 0.06
        lo, hi = data.layer_range(obj, self.bpy.context.scene)
        e = data.vertex_ease(obj, self.bpy.context.scene)
        e[patch] = self.rng.uniform(max(lo, 1.0), min(hi, 1.8))
        layer = me.color_attributes["ease"]
        if layer.domain == "POINT":
            layer.data.foreach_set("color", ramp.ease_to_color(e, lo, hi).astype(np.float32).ravel())
            me.update()
        self.bpy.context.view_layer.update()  # the stroke's redraw: Live's depsgraph handler sees it
        self.bpy.ops.ed.undo_push(message="stroke")  # a stroke is one undo step
        self.undo_ready = True

    def ease_to_design(self):
        self.op("ease_to_design")

    def ease_uniform(self):
        s = self.s
        try:
            names = [p.name for p in self.mod("data").current_cut(self.bpy.context).panels]
        except Exception:
            names = []
        if names:
            self.op("ease_uniform", panel=self.rng.choice(names), ease=round(self.rng.uniform(1.0, 1.6), 3))
        elif s.body is not None:
            self.op("ease_uniform", whole_body=True, ease=1.2)

    def live_toggle(self):
        if self.s.body is None or not self.s.design_json:
            return
        self.s.live = not self.s.live
        self.edited("live")

    def live_ticks(self):
        if not self.s.live:
            return
        live = self.mod("live")
        for _ in range(self.rng.randrange(1, 40)):
            if live._tick() is None:  # as the timer runs it: stopped (converged, or an error said)
                break

    def undo(self):
        if not self.undo_ready:
            return
        if self.bpy.ops.ed.undo.poll():
            self.bpy.ops.ed.undo()
            if self.rng.random() < 0.5 and self.bpy.ops.ed.redo.poll():
                self.bpy.ops.ed.redo()

    def optimize(self):
        self.op("optimize_pattern")

    def transfer(self):
        data = self.mod("data")
        self.s.fit_size = self.rng.choice(data.chart_sizes(data.design_chart(self.bpy.context.scene)))
        self.op("transfer_size")

    def adapt(self):
        self.s.adapt_P1, self.s.adapt_T = True, False
        self.op("adapt_poses")

    def drape(self):
        self.s.drape_frames, self.s.drape_device = 2, "cpu"
        self.op("drape")

    def export(self):
        self.s.export_dir = str(self.b.tmp / "walk_export")
        self.s.export_svg, self.s.export_dxf, self.s.export_pdf = True, False, False
        self.s.export_glb = self.s.export_obj = False
        self.op("export_pattern")

    def marker(self):
        self.s.export_dir = str(self.b.tmp / "walk_export")
        self.s.marker_seconds, self.s.marker_sizes = 1, ""
        self.op("marker")

    def render(self):
        s = self.s
        s.render_path = str(self.b.tmp / "walk_render.png")
        s.render_resolution, s.render_samples, s.render_view = 5, 1, "FRONT"
        self.op("render")

    MOVES = {  # move: (weight in CI, weight with --full)
        "add_body": (2, 2),
        "set_size": (4, 4),
        "set_pose": (4, 4),
        "load_template": (3, 4),
        "move_keypoint": (3, 4),
        "set_parameter": (6, 6),
        "paint": (8, 8),
        "ease_to_design": (3, 3),
        "ease_uniform": (3, 3),
        "live_toggle": (3, 3),
        "live_ticks": (5, 5),
        "undo": (4, 5),
        "optimize": (2, 3),
        "transfer": (1, 2),
        "adapt": (0, 1),
        "drape": (1, 1),
        "export": (1, 1),
        "marker": (0, 1),  # (CI weight 0: the CI seeds' sequences stay the ones that found bugs)
        "render": (0, 1),
    }

    def step(self):
        names = list(self.MOVES)
        weights = [self.MOVES[n][1 if self.full else 0] for n in names]
        move = self.rng.choices(names, weights)[0]
        if self.s.body is None and self.rng.random() < 0.8:
            move = "add_body"  # a designer starts from a body and a design
        elif not self.s.design_json and self.rng.random() < 0.8:
            move = "load_template"
        self.log.append(move)
        if TRACE:
            print(f"[walk] {len(self.log)} {move}", flush=True)
        getattr(self, move)()
        if self.s.live and self.rng.random() < 0.5:
            self.live_ticks()  # the timer runs between the designer's moves
        self.check()

    # -- invariants -----------------------------------------------------------------------------
    def check(self):
        state = self.mod("state")
        assert not state.BUGS, state.BUGS[-1][1]
        bpy = self.bpy
        s = self.s
        data = self.mod("data")
        names = (
            [o.name for o in bpy.data.objects] + [m.name for m in bpy.data.meshes] + [c.name for c in bpy.data.curves]
        )
        dup = [n for n in names if re.search(r"\.\d{3}$", n) and n.startswith("EASE")]
        assert not dup, dup
        assert s.size in data.chart_sizes(s.chart)
        if s.design_json:
            assert s.fit_size in data.chart_sizes(data.design_chart(bpy.context.scene))
        body = data.body_object(bpy.context, required=False)
        if body is not None:
            self._check_body(body)
        if s.design_json:
            self._check_design()
        if s.live and s.live_status.startswith("converged") and body is not None:
            self._check_live(body)

    def _check_body(self, body):
        from core.body.sizes import split_size

        s, data = self.s, self.mod("data")
        model = data.state.body_model(data.body_spec(body)["model"])
        shape = data.full_shape(model, data.body_spec(body)["shape"])
        sliders = {i.name: i.value for i in s.shape}
        assert sliders == pytest.approx({k: shape[k] for k in sliders}, abs=1e-5)
        assert s.pose == data.body_spec(body)["pose"]
        size = body.get("ease_size")
        if size is not None:  # the body's size record (the Body panel shows it) is its shape's
            split_size(size)
            from core.body.sizes import size_shape

            want = data.full_shape(model, size_shape(model, size))
            assert shape == pytest.approx(want, abs=1e-6), size
        if s.measurements_report:
            got = data.measurements(model, shape)
            for name, value in re.findall(r"(\w+) ([\d.]+) cm", s.measurements_report):
                assert abs(float(value) - got[name]) <= MEASURE_TOL_CM, (name, value, got[name])

    def _check_design(self):
        s, data = self.s, self.mod("data")
        design = data.current_design(self.bpy.context)
        assert sorted(i.name for i in s.design_params) == sorted(design.parameters)
        for i in s.design_params:
            assert data.as_typed(i.value) == pytest.approx(design.parameters[i.name].value, abs=1e-6), i.name

    def _check_live(self, body):
        live, data = self.mod("live"), self.mod("data")
        if not self.full and self.rng.random() < 0.7:
            return  # CI: the cold solve now and then
        session = live.session_for(self.bpy.context)
        cold = session.cold_pattern(*live.targets(body, self.bpy.context.scene))
        stored = data.stored_pattern(self.bpy.context.scene)
        assert stored is not None
        for p, q in zip(cold.panels, stored.panels):
            assert np.allclose(np.asarray(q.uv), p.uv, rtol=0, atol=1e-9), p.name


def _walk(blender, seed: int, steps: int, full: bool, threaded: bool = False):
    blender.reset()
    blender.mod("state").BUGS.clear()
    jobs = blender.mod("jobs")
    walk = Walk(blender, random.Random(seed), full)
    jobs.SYNCHRONOUS = not threaded
    try:
        for _ in range(steps):
            walk.step()
            if threaded and walk.rng.random() < 0.5:
                jobs.wait()  # the jobs started meanwhile land (Blender's poll), then the scene is checked
                walk.check()
    except BaseException as exc:
        raise AssertionError(
            f"seed {seed}{' (threaded)' if threaded else ''}, after {walk.log[-12:]} (step {len(walk.log)}): {exc}"
        ) from exc
    finally:
        jobs.wait()
        jobs.SYNCHRONOUS = True
        blender.scene.ease.live = False
    from collections import Counter

    print(f"seed {seed}: {Counter(walk.log)}; {Counter(r for _, r in walk.results)}")


def _cases():
    ci = [(seed, CI_STEPS, False, False) for seed in CI_SEEDS]
    ci += [(seed, CI_STEPS, False, True) for seed in THREADED_CI_SEEDS]
    full = [pytest.param(seed, FULL_STEPS, True, False, marks=pytest.mark.slow) for seed in FULL_SEEDS]
    full += [pytest.param(seed, FULL_STEPS, True, True, marks=pytest.mark.slow) for seed in THREADED_FULL_SEEDS]
    return ci + full


@pytest.mark.parametrize("seed, steps, full, threaded", _cases())
def test_designer_walk(blender, seed, steps, full, threaded):
    _walk(blender, seed, steps, full, threaded)
