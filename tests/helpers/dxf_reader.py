"""A small DXF reader independent of ezdxf: the second reader of the export tests.

It reads ASCII DXF as pairs of lines (group code, value), splits the
sections, and keeps what a pattern file holds: the HEADER variables, the
LAYER table, the BLOCKS with their entities and the ENTITIES, for LINE,
POINT, TEXT, LWPOLYLINE, POLYLINE (+ VERTEX ... SEQEND) and INSERT. Nothing
here shares code with ezdxf or core.export, so a file both readers agree on
is not read right only by the library that wrote it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

import numpy as np


@dataclass
class Entity:
    """One entity: its type, layer, group values in file order, and for polylines the points and closed flag."""

    kind: str
    layer: str = "0"
    tags: List[Tuple[int, str]] = field(default_factory=list)
    points: Optional[np.ndarray] = None
    closed: bool = False

    def value(self, code: int, default=None):
        for c, v in self.tags:
            if c == code:
                return v
        return default

    def number(self, code: int, default: float = 0.0) -> float:
        v = self.value(code)
        return default if v is None else float(v)


@dataclass
class Drawing:
    header: Dict[str, List[Tuple[int, str]]]
    layers: List[str]
    blocks: Dict[str, List[Entity]]
    entities: List[Entity]

    def header_number(self, name: str, code: int) -> Optional[float]:
        for c, v in self.header.get(name, []):
            if c == code:
                return float(v)
        return None


class DxfSyntaxError(ValueError):
    pass


def _pairs(text: str) -> List[Tuple[int, str]]:
    lines = text.splitlines()
    if len(lines) % 2:
        raise DxfSyntaxError(f"odd number of lines ({len(lines)}): group codes and values must pair up")
    out = []
    for k in range(0, len(lines), 2):
        try:
            code = int(lines[k].strip())
        except ValueError:
            raise DxfSyntaxError(f"line {k + 1}: group code expected, got {lines[k]!r}") from None
        out.append((code, lines[k + 1].strip()))
    return out


def _entities(pairs: List[Tuple[int, str]]) -> List[Entity]:
    """Entities of a run of pairs that starts at a (0, TYPE) pair; VERTEX/SEQEND folded into their POLYLINE."""
    ents: List[Entity] = []
    cur: Optional[Entity] = None
    poly: Optional[Entity] = None
    verts: List[Tuple[float, float]] = []
    for code, value in pairs:
        if code == 0:
            if cur is not None and cur.kind == "VERTEX" and poly is not None:
                verts.append((cur.number(10), cur.number(20)))
            cur = Entity(kind=value)
            if value == "SEQEND" and poly is not None:
                poly.points = np.array(verts, float).reshape(-1, 2)
                poly, verts, cur = None, [], None
            elif value == "POLYLINE":
                poly = cur
                ents.append(cur)
            elif value != "VERTEX":
                ents.append(cur)
            continue
        if cur is None:
            continue
        cur.tags.append((code, value))
        if code == 8:
            cur.layer = value
    for e in ents:
        if e.kind == "LWPOLYLINE":
            xs = [float(v) for c, v in e.tags if c == 10]
            ys = [float(v) for c, v in e.tags if c == 20]
            if len(xs) != len(ys):
                raise DxfSyntaxError(f"LWPOLYLINE on layer {e.layer}: {len(xs)} x but {len(ys)} y values")
            e.points = np.column_stack([xs, ys]) if xs else np.zeros((0, 2))
        if e.kind in ("LWPOLYLINE", "POLYLINE"):
            e.closed = bool(int(e.value(70, "0")) & 1)
            if e.points is None:
                raise DxfSyntaxError(f"POLYLINE on layer {e.layer} without SEQEND")
    return ents


def read(text: str) -> Drawing:
    """Parse an ASCII DXF; raise :class:`DxfSyntaxError` when it is not well formed."""
    pairs = _pairs(text)
    if not pairs or pairs[-1] != (0, "EOF"):
        raise DxfSyntaxError("the file does not end with 0/EOF")
    sections: Dict[str, List[Tuple[int, str]]] = {}
    k = 0
    while k < len(pairs) - 1:
        if pairs[k] != (0, "SECTION") or pairs[k + 1][0] != 2:
            raise DxfSyntaxError(f"pair {k}: expected 0/SECTION and its name, got {pairs[k]}")
        name = pairs[k + 1][1]
        end = pairs.index((0, "ENDSEC"), k)
        if name in sections:
            raise DxfSyntaxError(f"section {name} twice")
        sections[name] = pairs[k + 2 : end]
        k = end + 1
    header: Dict[str, List[Tuple[int, str]]] = {}
    var = None
    for code, value in sections.get("HEADER", []):
        if code == 9:
            var = value
            header[var] = []
        elif var is not None:
            header[var].append((code, value))
    layers = []
    in_layer_table = False
    tables = sections.get("TABLES", [])
    for i, (code, value) in enumerate(tables):
        if code == 0 and value == "TABLE":
            in_layer_table = i + 1 < len(tables) and tables[i + 1] == (2, "LAYER")
        elif in_layer_table and code == 0 and value == "LAYER":
            name = next((v for c, v in tables[i + 1 :] if c == 2), None)
            layers.append(name)
    blocks: Dict[str, List[Entity]] = {}
    run: List[Tuple[int, str]] = []
    name = None
    for code, value in sections.get("BLOCKS", []):
        if code == 0 and value == "BLOCK":
            run, name = [], None
            continue
        if code == 0 and value == "ENDBLK":
            blocks[name] = _entities(run)
            name = "\0"  # the ENDBLK's own tags are skipped
            continue
        if name is None and code == 2:
            name = value
            run = []
            continue
        if name is not None and name != "\0" and (code == 0 or run):
            run.append((code, value))
    return Drawing(header=header, layers=layers, blocks=blocks, entities=_entities(sections.get("ENTITIES", [])))


def polyline_length(points: np.ndarray, closed: bool) -> float:
    q = np.asarray(points, float)
    if closed:
        q = np.vstack([q, q[:1]])
    return float(np.linalg.norm(np.diff(q, axis=0), axis=1).sum())
