"""Scene properties of the add-on (saved in the .blend).

What must survive a save lives here or in custom properties of the body
object: the design JSON (with its ease field), the ease layer on the body
mesh, keypoint layers, the last pattern/fit/drape reports as JSON. The
update callbacks hand over to :mod:`.sync` (the after-change reactions).
"""

from __future__ import annotations

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    FloatProperty,
    FloatVectorProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

from ..core.body.sizes import CHARTS
from ..core.design.checks import EASE_MAX, EASE_MIN
from . import data, live, sync

# Every size name of every chart, in size order (the default chart's first); the panels offer the
# ones of the chart that applies (the Body panel's chart selector, the design's chart in Fit).
SIZES = [
    (s, s, f"size {s} of the chart ({', '.join(c.name for c in CHARTS.values() if s in c.sizes)})")
    for s in data.all_sizes()
]
CHART_ITEMS = [(c.name, c.name.capitalize(), f"{c.title}; sizes {', '.join(c.sizes)}") for c in CHARTS.values()]
#: the solver configurations (core.workflows.CONFIGS) as the pattern operators offer them, after the design's own
#: choice (its "solver" field, applied by the core: data.solver_choice)
SOLVER_CONFIGS = [
    (data.DESIGN_SOLVER, "Design's", 'the configuration the design names (its "solver" field), else Improved'),
    ("improved", "Improved", "20 local-global iterations, warp free within 12 %"),
    (
        "fitted",
        "Fitted",
        "darted, close-fitting garments: solved to convergence (300 iterations), "
        "the warp lengths nearly kept (about 15x the time)",
    ),
    ("stretch", "Stretch", "stronger weft feedback: compliance bought with shear and warp length"),
    (
        "lengths",
        "Lengths",
        "the design's lengths kept along the grain: weft and warp both close to "
        "the ease (warp within 3 %), for about twice the shear; not for skirts",
    ),
    ("paper", "Paper", "the EASE paper's weights taken literally"),
]
POSES = [
    ("A", "A", "reference A-pose"),
    ("T", "T", "T-pose"),
    ("P1", "P1", "arms forward, legs spread"),
    ("P2", "P2", "arms up, scissored legs"),
    ("P3", "P3", "sitting, elbows bent"),
]


def _shape_value_update(self, context):
    # Slider moved: update the body in place (no-op while the add-on itself fills the list).
    sync.shape_changed(self, context)


class EASE_PG_shape_param(bpy.types.PropertyGroup):
    value: FloatProperty(name="Value", update=_shape_value_update, precision=3)
    min: FloatProperty()
    max: FloatProperty()


def _param_update(self, context):
    sync.param_changed(self, context)


class EASE_PG_design_param(bpy.types.PropertyGroup):
    """One placement (0..1) or length (metres) parameter of the loaded design."""

    path: StringProperty(description="JSON path of the parameter in the design")
    kind: StringProperty()
    value: FloatProperty(name="Value", precision=3, update=_param_update)
    min: FloatProperty()
    max: FloatProperty()


class EASE_PG_legend(bpy.types.PropertyGroup):
    ease: FloatProperty(precision=2)
    color: FloatVectorProperty(subtype="COLOR", size=4, min=0.0, max=1.0)


def _live_update(self, context):
    live.toggled(context.scene, context)


def _ramp_update(self, context):
    sync.refresh_legend(context.scene)


def _fitmap_update(self, context):
    sync.apply_fitmap(context.scene)


def _chart_update(self, context):
    sync.chart_changed(context.scene)


def _template_items(self, context):
    return data.template_items()


class EASE_PG_scene(bpy.types.PropertyGroup):
    # Body
    body: PointerProperty(type=bpy.types.Object, name="Body", description="The body object the design is attached to")
    body_file: StringProperty(
        name="Body file", subtype="FILE_PATH", description="SMPL/SMPL-X .npz/.pkl or template .obj the user owns"
    )
    shape: CollectionProperty(type=EASE_PG_shape_param)
    chart: EnumProperty(
        name="Chart",
        items=CHART_ITEMS,
        default="default",
        update=_chart_update,
        description="Size chart of the size presets: Anny's own (default) or EN 13402-3 women's / men's",
    )
    size: EnumProperty(name="Size", items=SIZES, default="M")
    pose: EnumProperty(name="Pose", items=POSES, default="A")
    height_cm: FloatProperty(
        name="Height", default=170.0, min=100.0, max=230.0, unit="NONE", description="Target body height (cm)"
    )
    chest_cm: FloatProperty(
        name="Chest/bust", default=92.0, min=50.0, max=180.0, description="Target chest/bust circumference (cm)"
    )
    waist_cm: FloatProperty(
        name="Waist", default=76.0, min=40.0, max=180.0, description="Target waist circumference (cm)"
    )
    hip_cm: FloatProperty(name="Hip", default=98.0, min=50.0, max=180.0, description="Target hip circumference (cm)")
    measurements_report: StringProperty(name="Achieved measurements")
    # Design
    template: EnumProperty(
        name="Template", items=_template_items, description="Design templates shipped in examples/designs"
    )
    design_file: StringProperty(name="Design file", subtype="FILE_PATH")
    design_json: StringProperty(name="Design", description="The current design (JSON)")
    design_params: CollectionProperty(type=EASE_PG_design_param)
    design_status: StringProperty(
        name="Design status", description="Why the last parameter value was refused (empty: none was)"
    )
    live_recut: BoolProperty(name="Live re-cut", default=True, description="Re-cut the design when a parameter changes")
    keypoint_name: StringProperty(name="Keypoint", description="Keypoint to place on the selected vertex")
    # Ease
    ease_min: FloatProperty(name="Ramp min", default=0.9, min=EASE_MIN, max=EASE_MAX, update=_ramp_update)
    ease_max: FloatProperty(name="Ramp max", default=2.0, min=EASE_MIN, max=EASE_MAX, update=_ramp_update)
    ease_value: FloatProperty(
        name="Ease",
        default=1.3,
        min=EASE_MIN,
        max=EASE_MAX,
        description="Ease the brush paints (weft scale; 1.0 lies on the body)",
    )
    ease_panel: StringProperty(name="Panel", description="Panel whose ease the operators set")
    ease_from: FloatProperty(name="From", default=1.1, min=EASE_MIN, max=EASE_MAX)
    ease_to: FloatProperty(name="To", default=1.6, min=EASE_MIN, max=EASE_MAX)
    gradient_axis: EnumProperty(
        name="Axis",
        items=[("Z", "Top to bottom", ""), ("X", "Right to left", ""), ("Y", "Front to back", "")],
        default="Z",
    )
    legend: CollectionProperty(type=EASE_PG_legend)
    live: BoolProperty(
        name="Live",
        default=False,
        update=_live_update,
        description="Re-solve the pattern while you paint the ease layer; the pieces update in place "
        "and the body's ease_fit layer shows achieved over painted ease",
    )
    live_status: StringProperty(name="Live status")
    live_legend: CollectionProperty(type=EASE_PG_legend)
    job_status: StringProperty(
        name="Background work", description="What the add-on computes off the main thread (updating: ...)"
    )
    # Pattern / fit
    pattern_json: StringProperty(name="Pattern report", description="Key figures of the last pattern (JSON)")
    fit_size: EnumProperty(name="Target size", items=SIZES, default="L")
    adapt_P1: BoolProperty(name="P1", default=True)
    adapt_P2: BoolProperty(name="P2", default=False)
    adapt_P3: BoolProperty(name="P3", default=False)
    adapt_T: BoolProperty(name="T", default=False)
    tolerance: FloatProperty(
        name="Tolerance", default=1.1, min=1.0, max=2.0, description="Material stretch tolerance (epsilon_weft)"
    )
    fit_json: StringProperty(name="Fit report", description="Before/after residual stretch (JSON)")
    # Drape
    drape_status: StringProperty(name="Drape status")
    drape_json: StringProperty(name="Drape report")
    drape_frames: IntProperty(name="Max frames", default=200, min=1, max=5000)
    drape_device: EnumProperty(
        name="Device",
        items=[("cpu", "CPU", "bitwise repeatable"), ("cuda", "CUDA", "NVIDIA GPU through Warp")],
        default="cpu",
    )
    # the drape solver (core.drape.DrapeOptions.solver); "default": the core's own default
    drape_solver: EnumProperty(
        name="Solver",
        description="The drape solver of Drape and Drape Animation",
        items=[
            ("default", "Default", "the core's default drape solver (`ease drape` without --solver)"),
            ("xpbd", "XPBD", "fast, softer than the fabric"),
            ("pd", "PD", "projective dynamics: the fabric's own stiffness"),
        ],
        default="default",
    )
    # every pin held for the whole drape (core.drape.DrapeOptions.hold_pins); off: an upper garment's
    # collar lets go once the garment has grown, and the shirt hangs from its shoulders
    drape_hold_pins: BoolProperty(
        name="Hold Pins",
        description="Hold every pin for the whole drape (off: a shirt's collar lets go once it has grown to "
        "its pattern size and the shirt hangs from its shoulders; a waistband stays held)",
        default=False,
    )
    # the drape mesh's longest edge where the cloth hangs free (mm; 0: the pattern's mesh as it is);
    # the default is `ease drape --refine-edge`'s (core.cli.drape.REFINE_EDGE, 10 mm)
    drape_refine_mm: FloatProperty(
        name="Refine (mm)",
        description="Refine the drape mesh where the cloth hangs free to edges at most this long "
        "(finer folds, slower; 0: drape the pattern's mesh as it is)",
        default=10.0,
        min=0.0,
        max=100.0,
        step=100,
        precision=1,
    )
    # Drape Animation (Drape panel): the pose sequence, its in-betweens, the Alembic file
    motion_poses: StringProperty(
        name="Poses",
        default="A, P1, P3",
        description="pose presets the body moves through, the first the pattern's own",
    )
    motion_between: IntProperty(
        name="In-betweens", default=10, min=0, max=240, description="frames from each pose to the next"
    )
    motion_source: EnumProperty(
        name="Motion",
        items=[
            ("POSES", "Poses", "the pose presets in Poses, with In-betweens from each to the next"),
            ("ACTION", "Rig Action", "the body rig's keyframed bones over the scene's frame range (Add Rig)"),
        ],
        default="POSES",
    )
    motion_adapt: BoolProperty(
        name="Adapt to Poses",
        default=False,
        description="adapt the pattern to the motion's poses first (the design's stretch tolerances), "
        "then drape that pattern through the motion",
    )
    motion_status: StringProperty(name="Motion status")
    motion_path: StringProperty(name="Alembic to", subtype="FILE_PATH", default="//ease_motion.abc")
    motion_with_body: BoolProperty(name="With body", default=True, description="the body in the Alembic file too")
    fitmap: EnumProperty(
        name="Fit map",
        items=[
            ("NONE", "Fabric", "plain fabric material"),
            ("STRAIN", "Strain", "colour by weft strain"),
            ("GAP", "Gap", "colour by body-garment gap"),
        ],
        default="NONE",
        update=_fitmap_update,
    )
    # Render / export
    render_path: StringProperty(name="Render to", subtype="FILE_PATH", default="//ease_render.png")
    render_samples: IntProperty(
        name="Samples", default=32, min=1, max=4096, description="Cycles samples per pixel (adaptive, denoised)"
    )
    render_resolution: IntProperty(
        name="Resolution %", default=100, min=5, max=100, description="% of the studio's 1080 x 1440 frame"
    )
    render_view: EnumProperty(
        name="View",
        items=[
            ("FRONT", "Front", "the front camera"),
            ("THREE_QUARTER", "3/4", "the three-quarter camera (front right)"),
            ("BACK", "Back", "the back camera"),
            ("PATTERN", "Pattern", "the pattern pieces, flat"),
            ("ALL", "All", "front, 3/4 and back: one PNG each"),
        ],
        default="FRONT",
    )
    render_turntable_frames: IntProperty(
        name="Turntable frames", default=24, min=2, max=720, description="frames of a full turn around the body"
    )
    export_dir: StringProperty(name="Export to", subtype="DIR_PATH", default="//ease_export")
    export_svg: BoolProperty(name="SVG", default=True)
    export_dxf: BoolProperty(name="DXF", default=True)
    export_pdf: BoolProperty(name="PDF", default=False)
    export_glb: BoolProperty(name="GLB", default=False)
    export_obj: BoolProperty(name="OBJ", default=False)
    # marker (Render & Export panel): fabric width, garments per size, nesting time
    marker_width_mm: FloatProperty(
        name="Fabric width (mm)",
        default=1500.0,
        min=100.0,
        max=5000.0,
        precision=0,
        description="Usable fabric width, selvage to selvage, in millimetres",
    )
    marker_sizes: StringProperty(
        name="Sizes",
        default="",
        description="Garments per size, e.g. XS:1,M:2,L:1 (empty: one garment of the "
        "current pattern's size); other sizes are transferred first",
    )
    marker_seconds: IntProperty(
        name="Seconds",
        default=30,
        min=1,
        max=600,
        description="Time budget of the nester, used whole (the best marker found in it is kept)",
    )
    marker_one_way: BoolProperty(
        name="One-way fabric",
        default=False,
        description="Nap, pile or a directional print: every piece the same way up",
    )
    marker_spread: EnumProperty(
        name="Spread",
        items=[
            ("SINGLE", "Single ply", "one ply: every piece nested (ease marker --spread single)"),
            (
                "PAIRS",
                "Pairs, face to face",
                "two plies face to face, as cutting rooms lay mirrored pieces: one piece of each mirrored pair "
                "(the second ply cuts its mirror image), a piece that is its own mirror image half as often "
                "(ease marker --spread pairs)",
            ),
        ],
        default="SINGLE",
    )
    marker_status: StringProperty(name="Marker", default="")
    solver_config: EnumProperty(
        name="Solver",
        items=SOLVER_CONFIGS,
        default=data.DESIGN_SOLVER,
        description="Solver configuration of Optimize Pattern, Transfer to Size and Adapt "
        "to Poses: the design's own, or one chosen here over it (Live solves with it too)",
    )
    # seam gathering: kept in the design (materials.gather_above) by Optimize Pattern
    gather_auto: BoolProperty(
        name="Gather loose seams",
        default=True,
        description="Gather a seam whose two sides want lengths that differ by more than "
        "the threshold (a loose sleeve cap into its armhole) instead of sewing "
        "it flat at the price of shear",
    )
    gather_above_pct: FloatProperty(
        name="Above",
        default=20.0,
        min=1.0,
        max=500.0,
        precision=0,
        description="Gather a seam when one side wants this many percent more length than the other",
    )
    # seam allowance and notch spacing: kept in the design (materials.export) by Export Pattern
    export_allowance_cm: FloatProperty(
        name="Seam allowance",
        default=1.0,
        min=0.0,
        max=10.0,
        precision=2,
        description="Seam allowance (cm) of every seam without its own width in the design",
    )
    export_hem_cm: FloatProperty(
        name="Hem allowance", default=2.0, min=0.0, max=10.0, precision=2, description="Hem allowance (cm)"
    )
    export_notch_cm: FloatProperty(
        name="Notch spacing",
        default=10.0,
        min=0.0,
        max=100.0,
        precision=1,
        description="Notches along each seam every this many cm (0: seam ends only)",
    )
    export_print_all: BoolProperty(
        name="Print every piece",
        default=False,
        description="Tiled A4/Letter PDFs: print every piece whole (default: each "
        "mirrored pair once, cut 2, and symmetric pieces as halves on "
        "the fold)",
    )


CLASSES = (EASE_PG_shape_param, EASE_PG_design_param, EASE_PG_legend, EASE_PG_scene)


def register_props():
    bpy.types.Scene.ease = PointerProperty(type=EASE_PG_scene)


def unregister_props():
    if hasattr(bpy.types.Scene, "ease"):
        del bpy.types.Scene.ease
