"""Results: nodal frames per load step, reactions, probes and the versioned JSON schema.

Schema ``core-se3-result`` version 1 (written by ``--json``, read by every module):

    {"schema": "core-se3-result", "version": 1, "case", "model", "variant",
     "params": {key: {"value", "unit"}}, "mesh": {"nx", "ny", "n_nodes", "n_elements", "n_dofs"},
     "steps": [{"load_factor", "load": {"name", "value", "unit"},
                "probes": {name: {"u": [ux, uy, uz], "rotation_angle", "rotation_vector",
                                  "rotation": 3x3}},
                "iterations", "residual", "residual_history"}],
     "timings": {"setup", "assembly", "solve", "other", "total"},
     "reference": {"entry", "block", "error", "error_at"} or null}

``rotation_angle`` is |w| of the rotation vector of R R0^T unwrapped continuously along the
path (so a roll-up reports 6 pi, not its value modulo 2 pi).
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np

from . import se3

SCHEMA = "core-se3-result"
VERSION = 1

__all__ = ["StepResult", "Result", "Probe", "SCHEMA", "VERSION", "read_json", "write_json",
           "unwrap_rotation"]


def unwrap_rotation(R, w_prev):
    """Rotation vector of R that is closest to w_prev among w + 2 pi k n (continuity)."""
    w = se3.log_so3(R)
    t = np.linalg.norm(w)
    if t < 1e-12:
        n = w_prev / max(np.linalg.norm(w_prev), 1e-300) if np.linalg.norm(w_prev) > 0 else np.zeros(3)
        cands = [w + 2 * np.pi * k * n for k in range(-50, 51)] if np.linalg.norm(n) > 0 else [w]
    else:
        n = w / t
        cands = [w + 2 * np.pi * k * n for k in range(-50, 51)]
    cands = np.array(cands)
    return cands[np.argmin(np.linalg.norm(cands - w_prev, axis=1))]


@dataclass
class Probe:
    """A point of the mesh interpolated between two nodes (weights wa, wb = 1 - wa)."""
    name: str
    node_a: int
    node_b: int
    wa: float = 1.0

    def state(self, g):
        ga, gb = g[self.node_a], g[self.node_b]
        if self.node_a == self.node_b or self.wa == 1.0:
            return ga[:3, 3].copy(), ga[:3, :3].copy()
        rel = se3.log(se3.inv(ga) @ gb)
        gm = ga @ se3.exp((1.0 - self.wa) * rel)
        return gm[:3, 3].copy(), gm[:3, :3].copy()

    @classmethod
    def edge_midpoint(cls, name, nodes):
        nodes = list(nodes)
        k = len(nodes)
        if k % 2 == 1:
            return cls(name, nodes[k // 2], nodes[k // 2], 1.0)
        return cls(name, nodes[k // 2 - 1], nodes[k // 2], 0.5)


@dataclass
class StepResult:
    load_factor: float
    g: np.ndarray                      # (n, 4, 4) nodal frames
    iterations: int
    residual_history: list
    reaction_force: np.ndarray         # total lab reaction force at supports
    reaction_moment: np.ndarray        # total lab reaction moment about the origin
    applied_force: np.ndarray          # total applied lab force
    applied_moment: np.ndarray         # total applied lab moment about the origin
    probes: dict = field(default_factory=dict)   # name -> dict(u, R, w)
    scale: tuple = (0.0, 0.0)         # sums of nodal reaction/applied force and moment magnitudes

    @property
    def balance_error(self):
        """|reactions + applied| relative to the sum of the nodal force (moment) magnitudes."""
        sF = max(self.scale[0], np.linalg.norm(self.applied_force), 1e-300)
        sM = max(self.scale[1], np.linalg.norm(self.applied_moment), 1e-300)
        return max(np.linalg.norm(self.reaction_force + self.applied_force) / sF,
                   np.linalg.norm(self.reaction_moment + self.applied_moment) / sM)


@dataclass
class Result:
    mesh: object
    steps: list = field(default_factory=list)
    timings: dict = field(default_factory=lambda: dict(setup=0.0, assembly=0.0, solve=0.0, other=0.0))
    log: list = field(default_factory=list)      # per (sub)step diagnostics
    element: str = "default"

    @property
    def final(self):
        return self.steps[-1] if self.steps else None

    def displacements(self, k=-1):
        return self.steps[k].g[:, :3, 3] - self.mesh.X

    def timing_table(self):
        t = self.timings
        tot = sum(t.values())
        lines = [f"{'phase':<10}{'seconds':>10}{'share':>8}"]
        for key in ("setup", "assembly", "solve", "other"):
            lines.append(f"{key:<10}{t.get(key, 0.0):>10.3f}{100 * t.get(key, 0.0) / max(tot, 1e-300):>7.1f}%")
        lines.append(f"{'total':<10}{tot:>10.3f}")
        return "\n".join(lines)


def write_json(path, doc):
    with open(path, "w") as fh:
        json.dump(doc, fh, indent=1)


def read_json(path):
    with open(path) as fh:
        doc = json.load(fh)
    if doc.get("schema") != SCHEMA:
        raise ValueError(f"{path}: not a {SCHEMA} document")
    if doc.get("version") != VERSION:
        raise ValueError(f"{path}: schema version {doc.get('version')} (this code reads {VERSION})")
    return doc
