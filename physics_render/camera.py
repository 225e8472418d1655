"""A pinhole camera looking at a target from an elevation, azimuth and distance.

World axes are the engine's (z up). The eye sits at
    eye = target + distance (cos el cos az, cos el sin az, sin el)
and looks at the target with z as the up direction. A world point p has
camera coordinates (x right, y up, z forward)
    c = R (p - eye),  R = [right; up; forward]
and lands on the pixel
    u = W/2 + f c_x / c_z,   v = H/2 - f c_y / c_z,   f = (H/2) / tan(fov/2),
with u, v measured from the top-left corner of the picture (pixel i spans
[i, i + 1)). Points with c_z below `near` are behind the eye and get clipped.
"""

from dataclasses import dataclass

import numpy as np

NEAR = 0.05  # m: anything closer to the eye than this is clipped


@dataclass(frozen=True)
class Camera:
    target: tuple = (0.0, 0.0, 0.0)  # m, world
    distance: float = 5.0  # m, eye to target
    elevation: float = 20.0  # degrees above the xy plane
    azimuth: float = -70.0  # degrees from +x towards +y (−90: looking along +y)
    fov: float = 40.0  # vertical field of view, degrees
    width: int = 640  # pixels
    height: int = 480

    def __post_init__(self):
        if not (self.distance > NEAR and np.isfinite(self.distance)):
            raise ValueError(f"camera distance must be a number > {NEAR} m, got {self.distance}")
        if not 1.0 <= self.fov <= 170.0:
            raise ValueError(f"camera field of view must be within 1..170 degrees, got {self.fov}")
        if self.width < 16 or self.height < 16:
            raise ValueError(f"picture size must be at least 16x16 pixels, got {self.width}x{self.height}")
        if len(self.target) != 3 or not np.all(np.isfinite(self.target)):
            raise ValueError(f"camera target must be three finite numbers, got {self.target}")

    @property
    def eye(self):
        el, az = np.radians(self.elevation), np.radians(self.azimuth)
        direction = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
        return np.asarray(self.target, dtype=np.float64) + self.distance * direction

    @property
    def rotation(self):
        """Rows: the camera's right, up and forward axes in world coordinates."""
        forward = np.asarray(self.target, dtype=np.float64) - self.eye
        forward /= np.linalg.norm(forward)
        up_hint = np.array([0.0, 0.0, 1.0])
        if abs(forward @ up_hint) > 0.999:  # looking straight up or down: y is up on the picture
            up_hint = np.array([0.0, 1.0, 0.0])
        right = np.cross(forward, up_hint)
        right /= np.linalg.norm(right)
        up = np.cross(right, forward)
        return np.stack([right, up, forward])

    @property
    def focal(self):
        """Focal length in pixels."""
        return 0.5 * self.height / np.tan(0.5 * np.radians(self.fov))

    def to_camera(self, points):
        """(..., 3) world points -> (..., 3) camera coordinates (x right, y up, z forward)."""
        return (np.asarray(points, dtype=np.float64) - self.eye) @ self.rotation.T

    def to_pixels(self, cam):
        """(..., 3) camera coordinates (z > 0) -> (..., 2) pixel coordinates (u right, v down)."""
        cam = np.asarray(cam, dtype=np.float64)
        f = self.focal
        u = 0.5 * self.width + f * cam[..., 0] / cam[..., 2]
        v = 0.5 * self.height - f * cam[..., 1] / cam[..., 2]
        return np.stack([u, v], axis=-1)

    def project(self, points):
        """(..., 3) world points -> (..., 2) pixel coordinates; NaN behind the eye."""
        cam = self.to_camera(points)
        px = self.to_pixels(np.where(cam[..., 2:3] > NEAR, cam, np.nan))
        return px


def frame_scene(lo, hi, **camera):
    """A camera aimed at the middle of the box [lo, hi] (world, m) from far
    enough that the box's bounding sphere fits the narrower field of view,
    with a 10 % margin. Keys given in `camera` win over the framing."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    probe = Camera(**{k: v for k, v in camera.items() if k not in ("target", "distance")})
    target = 0.5 * (lo + hi)
    radius = max(0.5 * float(np.linalg.norm(hi - lo)), 0.25)
    half_fov = 0.5 * np.radians(probe.fov)
    half_fov = min(half_fov, np.arctan(np.tan(half_fov) * probe.width / probe.height))
    distance = 1.1 * radius / np.sin(half_fov)
    framed = {"target": tuple(target.tolist()), "distance": float(distance)}
    framed.update(camera)
    return Camera(**framed)
