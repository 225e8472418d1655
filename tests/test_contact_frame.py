"""The contact frame of every contact row: (n, t1, t2) is an orthonormal,
right-handed basis for any unit normal (contact_build.tangent_frame, Duff et
al. 2017), so friction acts in the tangent plane and nowhere else.

Regression guard for the mutation "second tangent not orthogonal to the
normal" (t2's last component with the wrong sign): every contact the other
tests make has a normal with n_y = 0 (floors, inclines tilted about y, hits
along x), where that sign does not show, and it survived them all.
"""
import numpy as np

from physics_core.collision.contact_build import tangent_frame
from physics_core.collision.contact_layout import DIR, NCOL, direction_columns


def _frames(normals):
    R = np.zeros((len(normals), NCOL))
    for c, (nx, ny, nz) in enumerate(normals):
        tangent_frame(R, c, nx, ny, nz)
    return R[:, direction_columns(DIR)].reshape(-1, 3, 3)     # rows n, t1, t2


def test_contact_frame_is_orthonormal_and_right_handed_for_any_normal():
    rng = np.random.default_rng(5)
    normals = rng.normal(size=(500, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    # and the axes, both ways, and the branch point n_z = 0
    normals = np.vstack([normals, np.eye(3), -np.eye(3), [[0.6, 0.8, 0.0], [0.0, -0.8, 0.6]]])
    F = _frames(normals)
    np.testing.assert_array_equal(F[:, 0], normals)
    # orthonormal to round-off: a few ulps of the unit components
    np.testing.assert_allclose(F @ F.transpose(0, 2, 1), np.broadcast_to(np.eye(3), F.shape), rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.cross(F[:, 1], F[:, 2]), F[:, 0], rtol=0, atol=1e-15)  # t1 × t2 = n
