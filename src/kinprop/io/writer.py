"""Write models and results; every file is written atomically (temp file + rename)."""

from __future__ import annotations

import csv
import io
import json
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from kinprop.engine import compile as compile_engine
from kinprop.engine.units import tree_coordinates
from kinprop.io.couplings import couplings_to_data
from kinprop.io.elements import elements_to_data, vehicle_to_data
from kinprop.io.hardpoints import model_to_hardpoints
from kinprop.io.loader import parse_text
from kinprop.io.loads import loads_to_data
from kinprop.io.points import written_points
from kinprop.model import Model


def atomic_write(path: str | Path, data: str | bytes) -> None:
    """Write ``data`` to ``path`` so that readers see the old file or the new one, never half."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)  # the CLI refuses a missing directory before this
    mode = "wb" if isinstance(data, bytes) else "w"
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as exc:  # name the file asked for, not the temporary one
        raise OSError(exc.errno, f"cannot write here ({exc.strerror})", str(path)) from None
    try:
        with os.fdopen(fd, mode) as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the file the usual mode
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _floats(a: Any) -> Any:
    return np.asarray(a, dtype=float).tolist()


def model_to_data(model: Model) -> dict[str, Any]:
    """Frame-style file data at full precision (floats round-trip exactly)."""
    mech = model.mechanism
    asm = compile_engine(mech)
    tree = set(asm.topology.tree_joints)
    deg = model.units.get("angle") == "deg"
    bodies: dict[str, Any] = {}
    for b in mech.bodies:
        spec: dict[str, Any] = {}
        if b.fixed:
            spec = {"fixed": True, "position": _floats(b.position), "orientation": _floats(b.orientation)}
        if b.points:
            spec["points"] = {
                k: v if isinstance(v, str) else _floats(v) for k, v in written_points(model, b, False).items()
            }
        bodies[b.name] = spec
    joints: dict[str, Any] = {}
    for j in mech.joints:
        spec = {"type": j.type, "bodies": [j.body_i, j.body_j]}
        if j.cut is not None:
            spec["cut"] = j.cut
        for f in ("s_i", "s_j", "C_i", "C_j", "length"):
            if f in j.fields:
                v = model.design[f"{j.name}.{f}"]
                spec[f] = float(v) if f == "length" else _floats(v)
        if j.name in model.coordinates:
            q = np.array(model.coordinates[j.name], dtype=float)
            if deg and j.name in tree:
                q = tree_coordinates(q, j.jtype.angle_indices, "deg", False)
            spec["q"] = _floats(q)
        joints[j.name] = spec
    return {
        "kinprop": 1,
        "name": mech.name,
        "units": dict(model.units),
        "bodies": bodies,
        "joints": joints,
        **({"inputs": list(mech.inputs)} if mech.inputs else {}),
        **({"couplings": couplings_to_data(model)} if mech.couplings else {}),
        **({"edits": mech.edits} if mech.edits != "mechanism" else {}),
        **(
            {"elements": elements_to_data(model.elements, "frames", None, model.torsion_springs)}
            if model.elements or model.torsion_springs
            else {}
        ),
        **({"vehicle": vehicle_to_data(model.vehicle)} if model.vehicle is not None else {}),
        **({"loads": loads_to_data(model.loads, "frames")} if model.loads is not None else {}),
    }


class _PlainDumper(yaml.SafeDumper):
    """YAML without anchors and aliases (``&id001``): a value shared in memory is written out
    again where it repeats, as a person would write it."""

    def ignore_aliases(self, data: Any) -> bool:
        return True


def yaml_text(data: Any, width: int = 100) -> str:
    """YAML of file data: leaf lists inline, keys in order, no anchors, full precision."""
    return yaml.dump(data, Dumper=_PlainDumper, sort_keys=False, default_flow_style=None, width=width)


def dump_model(model: Model, path: str | Path) -> None:
    data = model_to_data(model)
    text = json.dumps(data, indent=2) if str(path).endswith(".json") else yaml_text(data)
    atomic_write(path, text)


def _csv_cell(v: Any) -> Any:
    """Shortest round-trip text for numbers (``repr``), empty for NaN, as-is otherwise."""
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    if isinstance(v, (float, np.floating)):
        v = float(v)
        return "" if v != v else repr(v)
    if isinstance(v, np.integer):
        return int(v)
    return v


def csv_text(columns: list[str], rows: list[dict[str, Any]]) -> str:
    """CSV with a header row, ``\\n`` line endings and shortest round-trip numbers."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for row in rows:
        w.writerow([_csv_cell(row.get(c)) for c in columns])
    return buf.getvalue()


def model_text(data: dict[str, Any], path: str | Path | None) -> str:
    """File text of model data: JSON for ``*.json``, else YAML (leaf lists inline), full precision."""
    if path is not None and str(path).endswith(".json"):
        return json.dumps(data, indent=2) + "\n"
    return yaml_text(data)


def file_style(path: str | Path) -> tuple[str, str]:
    """``(style, body_frames)`` of a model file: ``("frames", "")`` or ``("hardpoints", "global"|"joint")``."""
    data = parse_text(Path(path).read_text(encoding="utf-8"), str(path))
    if isinstance(data, dict) and data.get("style") == "hardpoints":
        return "hardpoints", str(data.get("body_frames", "global"))
    return "frames", ""


def dump_model_like(model: Model, path: str | Path, like: str | Path | None) -> None:
    """Write ``model`` in the style of the file ``like`` (the input): a hardpoint-style input
    gives a hardpoint-style output (same ``body_frames`` rule), a frame-style one frames; a
    YAML output of a YAML input keeps the input's comments, key order and inline lists
    (:func:`commented_text`)."""
    style, body_frames = file_style(like) if like is not None else ("frames", "")
    data = model_to_hardpoints(model, body_frames) if style == "hardpoints" else model_to_data(model)
    text = None
    if like is not None and not str(path).endswith(".json") and not str(like).endswith(".json"):
        text = commented_text(Path(like).read_text(encoding="utf-8"), data)
    atomic_write(path, text if text is not None else model_text(data, path))


def _pyyaml_float(representer: Any, value: float) -> Any:
    """A float as PyYAML writes it (``1.0e-05``, ``.inf``, ``.nan``; shortest round trip), so
    the loader (PyYAML, YAML 1.1, where ``1e-05`` is a string) reads it back as the number."""
    if value != value:
        text = ".nan"
    elif value in (float("inf"), float("-inf")):
        text = ".inf" if value > 0 else "-.inf"
    else:
        text = repr(float(value))
        if "e" in text and "." not in text.split("e")[0]:
            mant, exp = text.split("e")
            text = f"{mant}.0e{exp}"
    return representer.represent_scalar("tag:yaml.org,2002:float", text)


def _leaf_list(v: Any) -> bool:
    return isinstance(v, list) and all(not isinstance(x, (list, dict)) for x in v)


def _fresh(v: Any) -> Any:
    """New file data as ruamel nodes: mappings in block style, lists of numbers inline."""
    from ruamel.yaml.comments import CommentedMap, CommentedSeq

    if isinstance(v, dict):
        out = CommentedMap()
        for k, x in v.items():
            out[k] = _fresh(x)
        return out
    if isinstance(v, list):
        seq = CommentedSeq(_fresh(x) for x in v)
        if _leaf_list(v) or all(_leaf_list(x) for x in v):
            seq.fa.set_flow_style()
        return seq
    return v


def _merge(old: Any, new: Any) -> Any:
    """``new`` written into ``old`` (a ruamel node): same keys keep their comments and place,
    gone keys are removed, new keys are appended; lists of the same length are updated in
    place (their style and comments kept)."""
    from ruamel.yaml.comments import CommentedMap, CommentedSeq

    if isinstance(old, CommentedMap) and isinstance(new, dict):
        for k in [k for k in old if k not in new]:
            del old[k]
        for k, v in new.items():
            old[k] = _merge(old[k], v) if k in old else _fresh(v)
        return old
    if isinstance(old, CommentedSeq) and isinstance(new, list) and len(old) == len(new):
        for i, v in enumerate(new):
            old[i] = _merge(old[i], v)
        return old
    if not isinstance(old, (dict, list, bool)) and not isinstance(new, (dict, list, bool)) and old == new:
        return old  # the same number or text: written as the file had it (3300, not 3300.0)
    return _fresh(new)


def commented_text(original: str, data: dict[str, Any], width: int = 100) -> str | None:
    """YAML of ``data`` laid over the ``original`` file's text with ruamel.yaml's round trip:
    its comments, key order and list styles are kept for every key that is still there, the
    values are ``data``'s (full precision). None when the original is not a YAML mapping."""
    from ruamel.yaml import YAML
    from ruamel.yaml.error import YAMLError

    y = YAML()  # round trip
    y.width = width
    y.representer.add_representer(float, _pyyaml_float)
    try:
        doc = y.load(original)
    except YAMLError:
        return None
    if not isinstance(doc, dict):
        return None
    buf = io.StringIO()
    y.dump(_merge(doc, data), buf)
    return buf.getvalue()
