"""core.cli: the `ease` command line (subcommands, errors, bench, demo, templates)."""

import pytest

from core import cli
from core.cli.demo import _steps
from core.design.templates import list_templates, template_path


def _subcommands():
    parser = cli.build_parser()
    action = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    return parser, action.choices


def test_every_stage_has_a_subcommand_with_help(capsys):
    _, choices = _subcommands()
    assert {"body", "cut", "pattern", "transfer", "adapt", "drape", "export", "bench", "demo"} <= set(choices)
    for name in choices:
        with pytest.raises(SystemExit) as e:
            cli.main([name, "--help"])
        assert e.value.code == 0
        out = capsys.readouterr().out
        assert out.startswith(f"usage: ease {name}"), name


def test_help_loads_no_pipeline():
    """``ease --help`` and the parsers import no numpy and no stage: start-up stays a bare interpreter's."""
    import subprocess
    import sys

    code = (
        "import sys; import core.cli; core.cli.build_parser().format_help(); "
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('numpy', 'scipy', 'warp') "
        "or m.split('.')[:2] in (['core', 'body'], ['core', 'design'], ['core', 'pattern'])))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_body_help_lists_the_size_charts(capsys):
    with pytest.raises(SystemExit):
        cli.build_parser().parse_args(["body", "--help"])
    out = capsys.readouterr().out
    assert "women: XS" in out and "men: XS" in out


def test_no_command_prints_help_and_fails(capsys):
    assert cli.main([]) == 1
    assert "COMMAND" in capsys.readouterr().out


def test_core_errors_exit_2_with_one_clear_line(tmp_path, capsys):
    rc = cli.main(["cut", str(tmp_path / "missing.json"), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.startswith("ease cut: error:") and "missing.json" in err
    assert not (tmp_path / "out").exists()


def test_every_demo_step_parses(tmp_path):
    parser = cli.build_parser()
    for quick in (False, True):
        titles = []
        for title, argv in _steps(tmp_path, quick):
            args = parser.parse_args(argv)
            assert callable(args.func), title
            titles.append(argv[0])
        assert titles == ["body", "cut", "pattern", "transfer", "adapt", "drape", "export"]
    export = dict(_steps(tmp_path, False))["export: SVG, DXF, PDF, GLB, OBJ"]
    assert export[export.index("--format") + 1] == "all"


def test_bench_runs_a_benchmark_and_indexes_every_report(tmp_path, monkeypatch, capsys):
    bench_dir = tmp_path / "benchmarks"
    bench_dir.mkdir()
    (bench_dir / "bench_alpha.py").write_text(
        "def run(out_dir, quick=False):\n    (out_dir / 'alpha.md').write_text('quick' if quick else 'full')\n"
    )
    (bench_dir / "bench_beta.py").write_text("def run(out_dir):\n    (out_dir / 'beta.md').write_text('b')\n")
    out = bench_dir / "results"
    assert cli.main(["bench", "--only", "alpha", "--quick", "--bench-dir", str(bench_dir)]) == 0
    assert (out / "alpha.md").read_text() == "quick"
    monkeypatch.chdir(tmp_path)  # ./benchmarks is the default
    assert cli.main(["bench", "--only", "beta"]) == 0
    index = (out / "README.md").read_text()
    assert "[alpha.md](alpha.md)" in index and "(quick)" in index and "[beta.md](beta.md)" in index
    capsys.readouterr()
    assert cli.main(["bench", "--only", "gamma", "--out", str(out)]) == 2
    assert "unknown benchmark(s) gamma; available: alpha, beta" in capsys.readouterr().err


def test_bench_outside_a_checkout_is_one_clear_line(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("EASE_BENCH_DIR", raising=False)
    assert cli.main(["bench"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ease bench: error: no benchmarks folder") and err.count("\n") == 1


def test_templates_lists_every_shipped_design(capsys):
    assert cli.main(["templates"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == list_templates()
    for line, name in zip(lines, list_templates()):
        assert line.split()[1] == str(template_path(name)) and template_path(name).is_file()


def test_demo_skips_the_render_outside_a_checkout(tmp_path, monkeypatch, capsys):
    from core.cli.demo import run_demo

    monkeypatch.chdir(tmp_path)
    steps = []
    assert run_demo(tmp_path / "demo", lambda argv: steps.append(argv[0]) or 0) == 0
    assert steps == ["body", "cut", "pattern", "transfer", "adapt", "drape", "export"]
    assert "render skipped" in capsys.readouterr().err
