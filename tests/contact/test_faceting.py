"""The chord depth of quadratic faces estimated from the vertex normals (contact/faceting.py)."""
from __future__ import annotations

import numpy as np
import pytest

from dolfinx_friction.contact.faceting import chord_depths
from dolfinx_friction.contact.shapes import FACE_TYPES


@pytest.mark.parametrize("angle", [0.01, 0.1, 0.4])
def test_sagitta_of_a_circular_arc(angle):
    """An L3 segment whose ends lie on a circle of radius R = 2 with the circle's normals:
    the sagitta R (1 - cos(angle/2)) to its fourth order (h^2/8R), on any side of the
    circle; a crease of 45 degrees (|n_b - n_a| = 0.77 > 0.5) counts 0."""
    R = 2.0
    for start in (0.0, 1.0, 3.0):
        t = np.array([start, start + angle])
        n = np.stack([np.cos(t), np.sin(t)], axis=-1)
        x = np.vstack([R * n, R * n.mean(axis=0)])  # the mid-side node on the chord
        depth = chord_depths(FACE_TYPES["L3"], x[None], n[None])
        exact = R * (1.0 - np.cos(angle / 2))
        assert depth[0, 0] == pytest.approx(exact, rel=0.1 * angle ** 2 + 1e-12)
    n = np.array([[[0.0, 1.0], [np.sin(np.pi / 4), np.cos(np.pi / 4)]]])
    x = np.array([[[0.0, 0.0], [1.0, 0.0], [0.5, 0.0]]])
    assert chord_depths(FACE_TYPES["L3"], x, n)[0, 0] == 0.0


def test_flat_faces_have_no_depth():
    """T6 and Q9 faces on a plane with one normal: depth 0 on every edge."""
    for name in ("T6", "Q9"):
        face = FACE_TYPES[name]
        x = np.zeros((1, face.n_nodes, 3))
        x[0, :, :2] = face.nodes
        nv = {"T6": 3, "Q9": 4}[name]
        n = np.tile([0.0, 0.0, 1.0], (1, nv, 1))
        assert np.all(chord_depths(face, x, n) == 0.0)
