"""A mirrored design whose per-triangle ease differs on the right side from the mirror of the left
(issue 32): the generated ``*_right`` panels read the ``*_left`` field at the mirror triangles, so
the right side's own values would be dropped without a word. Such a design is refused in one line
naming the field (the core, ``ease cut``, the add-on's Load Design); a symmetric field, or one that
lists the left side only, is cut as before."""

from __future__ import annotations

import json

import numpy as np
import pytest

import core.cli
from core.design import apply_ease, load_design
from core.design.mirror import face_symmetry
from core.design.templates import TEMPLATES
from core.errors import DesignError

TEMPLATE = "top_short_sleeve"  # mirrored: sleeve_front_right / sleeve_back_right are generated
SLEEVE = 2  # garments[0].panels[2]: sleeve_front_left
PATH = f"garments[0].panels[{SLEEVE}].ease.per_triangle"


@pytest.fixture(scope="module")
def prep(anny):
    from core import workflows as wf

    return wf.prepare(TEMPLATES[TEMPLATE](), body=anny)


def _arms(anny):
    faces = np.asarray(anny.faces)
    left = np.flatnonzero(np.isin(faces, anny.regions["arm_left"]).all(axis=1))
    fs = face_symmetry(faces, np.asarray(anny.symmetry))
    right = fs[left]
    return left[right >= 0], right[right >= 0]


def mirrored_sleeve_design(anny, right_value, listed="both"):
    """The template with the left front sleeve's ease per triangle: 1.5 on the left arm and
    ``right_value`` on its mirror triangles (the right arm); ``listed``: which side the field lists."""
    left, right = _arms(anny)
    d = TEMPLATES[TEMPLATE]()
    tris = {"both": np.r_[left, right], "left": left}[listed]
    vals = {"both": np.r_[np.full(len(left), 1.5), np.full(len(right), right_value)], "left": np.full(len(left), 1.5)}
    d["garments"][0]["panels"][SLEEVE]["ease"] = {
        "per_triangle": {"triangles": tris.tolist(), "values": vals[listed].tolist(), "default": 1.2}
    }
    return d


def test_right_side_paint_is_refused_naming_the_field(anny, prep):
    d = mirrored_sleeve_design(anny, 1.8)
    with pytest.raises(DesignError) as exc:
        apply_ease(prep.cut, d, anny, prep.reference)
    assert exc.value.path == PATH
    assert "sleeve_front_right" in str(exc.value) and "symmetric" in str(exc.value)


@pytest.mark.parametrize("right_value, listed", [(1.5, "both"), (None, "left")])
def test_symmetric_or_left_only_fields_keep_the_mirror(anny, right_value, listed):
    from core import workflows as wf

    d = mirrored_sleeve_design(anny, right_value, listed)
    c = wf.prepare(d, body=anny).cut
    left, right = c.panel("top.sleeve_front_left"), c.panel("top.sleeve_front_right")
    assert right.mirror_of == "top.sleeve_front_left"
    assert (right.ease == 1.5).sum() == (left.ease == 1.5).sum() > 0


def test_ease_cut_refuses_it_in_one_line(anny, tmp_path, capsys):
    bad = tmp_path / "asym.json"
    bad.write_text(json.dumps(mirrored_sleeve_design(anny, 1.8)))
    out = tmp_path / "out"
    code = core.cli.main(["cut", str(bad), "--out", str(out), "--no-png", "--quiet"])
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert PATH in lines[0] and "sleeve_front_right" in lines[0]
    assert not out.exists()
    assert load_design(mirrored_sleeve_design(anny, 1.8))  # the file itself is valid: it is the mirror that drops paint
