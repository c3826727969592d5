"""A run's rows reduced to what a source's claims read: per sequence (scene, camera path,
pipeline label, parameters), the mean of every numeric column over its scored frames."""

from __future__ import annotations

import json
import math


def sequence_means(rows: list[dict]) -> list[dict]:
    """One dict per sequence: its ``scene``, ``camera_path``, ``pipeline``, ``params`` and
    ``frames``, and the mean over its frames of each column that is a finite-or-infinite
    number in all of them (booleans kept when all frames agree)."""
    groups: dict = {}
    for r in rows:
        key = (r.get("scene"), r.get("camera_path"), r.get("pipeline"),
               json.dumps(r.get("params") or {}, sort_keys=True))
        groups.setdefault(key, []).append(r)
    out = []
    for (scene, path, label, params), rs in groups.items():
        mean = {"scene": scene, "camera_path": path, "pipeline": label,
                "params": json.loads(params), "frames": len(rs)}
        for k in rs[0]:
            vals = [r.get(k) for r in rs]
            if all(isinstance(v, bool) for v in vals) and len(set(vals)) == 1:
                mean.setdefault(k, vals[0])
            elif all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in vals):
                mean.setdefault(k, math.fsum(vals) / len(vals))
            elif all(isinstance(v, str) for v in vals) and len(set(vals)) == 1:
                mean.setdefault(k, vals[0])
        out.append(mean)
    return out
