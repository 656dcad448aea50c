"""A design names the solver configuration it is made for (``"solver"``): parsed, written back,
refused when it is not one, and honoured by every door through core.workflows unless the user
chooses one (``--config`` given, the add-on's Solver set to a configuration)."""

import json

import pytest

from core import workflows as wf
from core.cli import main
from core.design import load_design
from core.design.checks import SOLVER_CONFIGS
from core.design.templates import TEMPLATES
from core.errors import DesignError, PatternError
from core.pattern.config import SolverConfig


def _top(**fields):
    d = TEMPLATES["top_sleeveless"]()
    d.update(fields)
    return d


@pytest.mark.parametrize("name", SOLVER_CONFIGS)
def test_every_configuration_parses_and_round_trips(name):
    design = load_design(_top(solver=name))
    assert design.solver == name
    assert design.to_json()["solver"] == name
    assert load_design(design.to_json()).solver == name


def test_absent_is_none_and_not_written():
    design = load_design(_top())
    assert design.solver is None and "solver" not in design.to_json()
    assert load_design(_top(solver=None)).solver is None


def test_the_design_format_names_the_solvers_presets():
    """The names the format accepts are the presets the solver builds, and no other."""
    for name in SOLVER_CONFIGS:
        SolverConfig.named(name)
    with pytest.raises(PatternError) as err:
        SolverConfig.named("nonsense")
    listed = str(err.value).split("expected one of ", 1)[1].split(", got", 1)[0].split(", ")
    assert sorted(listed) == sorted(SOLVER_CONFIGS) == sorted(wf.CONFIGS)


@pytest.mark.parametrize("value", ["fast", "Fitted", 3, True, ["fitted"], {"name": "fitted"}])
def test_a_bad_solver_is_refused_at_its_path(value):
    with pytest.raises(DesignError) as err:
        load_design(_top(solver=value))
    assert err.value.path == "solver"
    assert "expected a solver configuration (improved, paper, stretch, fitted, lengths)" in err.value.message


def test_the_cli_refuses_a_bad_solver_in_one_line(tmp_path, capsys):
    """The project's bad-input rule: exit status 2 and one line naming the file, the field and what
    is expected; nothing written."""
    path = tmp_path / "blouse.json"
    path.write_text(json.dumps(_top(solver="fast")))
    assert main(["pattern", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith(f"ease pattern: error: {path}: solver: expected a solver configuration")
    assert err[0].endswith('got "fast"')
    assert not (tmp_path / "out").exists()


def test_precedence_caller_then_design_then_default():
    fitted = load_design(_top(solver="fitted"))
    plain = load_design(_top())
    assert wf.config_name(fitted) == "fitted"
    assert wf.config_name(fitted, "stretch") == "stretch"  # the user's choice wins
    assert wf.config_name(plain) == wf.DEFAULT_CONFIG == "improved"
    assert wf.config_name(plain, "paper") == "paper"
    assert wf.config_name(_top(solver="lengths")) == "lengths"  # a design dict (the batch's)
    assert wf.config_name({}) == "improved"


def test_the_cli_leaves_the_choice_to_the_design_unless_given():
    from core.cli import build_parser

    for cmd in (
        ["pattern", "d.json", "--out", "o"],
        ["transfer", "d.json", "--out", "o", "--size", "L"],
        ["adapt", "d.json", "--out", "o", "--pose", "P1"],
        ["batch", "d.json", "--out", "o", "--sample", "2"],
    ):
        assert build_parser().parse_args(cmd).config is None, cmd
        assert build_parser().parse_args(cmd + ["--config", "paper"]).config == "paper", cmd


@pytest.fixture(scope="module")
def stretched(anny):
    """The sleeveless top naming ``stretch`` (a cheap configuration that differs from improved), cut."""
    return wf.prepare(_top(solver="stretch"), body=anny)


def test_the_workflows_solve_with_the_designs_configuration(stretched):
    solver = wf.make_solver(stretched)
    assert solver.config == SolverConfig.stretch()
    run = wf.reference(stretched, solver=solver)
    assert run.pattern.report["config"] == "stretch"
    # the user's overrides apply to the design's configuration: its iterations, the rest kept
    assert wf.make_solver(stretched, iterations=3).config == SolverConfig.stretch(iterations=3)
    assert wf.make_solver(stretched, "improved").config == SolverConfig.improved()


def test_the_designs_configuration_is_solved_not_relabelled(stretched):
    """The design's configuration and the user's explicit one give different patterns, each recorded
    as what it is; the same as naming the design's configuration explicitly, to the bit."""
    own = wf.reference(stretched, iterations=3)
    named = wf.reference(stretched, "stretch", iterations=3)
    chosen = wf.reference(stretched, "improved", iterations=3)
    assert own.pattern.report["config"] == named.pattern.report["config"] == "stretch"
    assert chosen.pattern.report["config"] == "improved"
    for a, b, c in zip(own.pattern.panels, named.pattern.panels, chosen.pattern.panels):
        assert a.uv.tobytes() == b.uv.tobytes()
        assert a.uv.tobytes() != c.uv.tobytes()


# ----------------------------------------------------------------------------- a transfer's solver on the target


def test_the_transfer_solver_is_checked_and_chosen_on_the_cli():
    from core.cli import build_parser

    assert SolverConfig.improved().convergence.transfer_solver == "reference"
    SolverConfig.improved(transfer_solver="target").check()
    with pytest.raises(PatternError, match="convergence.transfer_solver: expected 'reference' or 'target'"):
        SolverConfig.improved(transfer_solver="nowhere").check()
    with pytest.raises(PatternError, match="convergence.transfer_solver"):
        wf.with_transfer_solver(SolverConfig.improved(), "M")
    cmd = ["transfer", "d.json", "--out", "o", "--size", "L"]
    assert build_parser().parse_args(cmd).transfer_solver is None
    assert build_parser().parse_args(cmd + ["--transfer-solver", "target"]).transfer_solver == "target"


def test_ease_transfer_passes_the_transfer_solver_on(tmp_path, monkeypatch):
    """``ease transfer --transfer-solver target`` reaches workflows.transfer (left out: None, the configuration's)."""
    seen = []
    monkeypatch.setattr(wf, "prepare", lambda design, progress=None: "prep")
    monkeypatch.setattr(wf, "transfer", lambda prep, size, **options: seen.append(options["transfer_solver"]))
    monkeypatch.setattr(wf, "write_pattern", lambda out, run, preview=True: None)
    monkeypatch.setattr(wf, "summary", lambda run: "")
    cmd = ["transfer", "d.json", "--out", str(tmp_path), "--size", "L", "--quiet"]
    assert main(cmd + ["--transfer-solver", "target"]) == 0 and main(cmd) == 0
    assert seen == ["target", None]


def test_a_target_solver_made_on_the_reference_body_is_the_reference_solver(stretched):
    """Flattened and factorised on the reference body's own positions, a transfer's target solver is the
    reference solver: a transfer onto that body gives the same bits either way."""
    from core.pattern.solve import transfer_pattern

    solver = wf.make_solver(stretched, iterations=3)
    cut, body = stretched.cut, stretched.reference
    ref = wf.reference(stretched, solver=solver).pattern
    on_ref = transfer_pattern(cut, body, body, solver=solver, start=ref)
    cfg = wf.with_transfer_solver(solver.config, "target")
    on_target = transfer_pattern(cut, body, body, cfg, solver=solver, start=ref)
    for a, b in zip(on_ref.panels, on_target.panels):
        assert a.uv.tobytes() == b.uv.tobytes()


def test_the_shirt_graded_to_xs_on_a_solver_made_there_is_within_the_target(anny):
    """Issue 37's closed-compliance target (1.2 %) on the shirt graded to XS, as shirt_box_pleat reads it: with the
    solver made on M (the reference's flattening and factorisation) 1.27 %; made on XS 1.15 % (1.12 started from
    XS's flattening; the shirt cut on XS itself 1.07), its warp and shear no worse (docs/darts.md)."""
    prep = wf.prepare(TEMPLATES["shirt_long_sleeve"](), body=anny)
    solver = wf.make_solver(prep)
    ref = wf.reference(prep, solver=solver).pattern
    runs = {s: wf.transfer(prep, "XS", solver=solver, start=ref, transfer_solver=s) for s in ("reference", "target")}
    c = {s: r.pattern.report["metrics"]["compliance"] for s, r in runs.items()}
    assert runs["target"].pattern.report["transfer_solver"] == "target"
    assert c["reference"]["mean"] > 1.2 >= c["target"]["mean"], c
    assert c["target"]["warp_mean"] <= c["reference"]["warp_mean"] + 0.05
    assert c["target"]["shear_p95"] <= c["reference"]["shear_p95"] + 0.05
    assert runs["target"].figures["flipped"] == 0


def test_a_design_names_its_transfer_solver_and_a_bad_one_is_refused_at_its_path():
    design = load_design(_top(transfer_solver="target"))
    assert design.transfer_solver == "target" and design.to_json()["transfer_solver"] == "target"
    assert load_design(design.to_json()).transfer_solver == "target"
    plain = load_design(_top())
    assert plain.transfer_solver is None and "transfer_solver" not in plain.to_json()
    for value in ("M", "Target", 1, ["target"]):
        with pytest.raises(DesignError) as err:
            load_design(_top(transfer_solver=value))
        assert err.value.path == "transfer_solver"
        assert "expected 'reference' or 'target' or 'cup' or null" in err.value.message


def test_the_transfer_takes_the_designs_transfer_solver_unless_the_caller_names_one(stretched, monkeypatch):
    """workflows.transfer: the caller's ``transfer_solver``, else the design's, else the configuration's; the
    report records the one used. shirt_box_pleat names ``"target"`` (issue 37: its XS at 1.15 %, not 1.27)."""
    import dataclasses

    from core.pattern import solve

    assert TEMPLATES["shirt_box_pleat"]()["transfer_solver"] == "target"
    seen = []
    real = solve.transfer_pattern

    def spy(*args, **kwargs):
        seen.append(None if kwargs.get("config") is None else kwargs["config"].convergence.transfer_solver)
        return real(*args, **kwargs)

    monkeypatch.setattr(solve, "transfer_pattern", spy)
    solver = wf.make_solver(stretched, iterations=2)
    ref = wf.reference(stretched, solver=solver).pattern
    named = dataclasses.replace(stretched, design=dataclasses.replace(stretched.design, transfer_solver="target"))
    runs = [
        wf.transfer(stretched, "S", solver=solver, start=ref),
        wf.transfer(named, "S", solver=solver, start=ref),
        wf.transfer(named, "S", solver=solver, start=ref, transfer_solver="reference"),
    ]
    assert seen == [None, "target", "reference"]
    assert [r.pattern.report["transfer_solver"] for r in runs] == ["reference", "target", "reference"]
