"""One picture of one frame: matplotlib's Agg canvas in pixel coordinates,
filled back to front (painter's algorithm) with what `geometry` outlines
and `Camera` projects.

Why matplotlib and not mplot3d or a GL renderer: mplot3d keeps its own
projection (not a camera a test can compute, and it sorts whole collections,
not faces, by depth), and a GL context needs a display or GPU drivers that a
pip-only install does not have. Agg is antialiased, headless and already a
dependency; the scenes here are spheres, boxes and planes, which a depth
sort of convex pieces draws correctly unless bodies interpenetrate.
"""

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.figure import Figure

from physics_core.contact_events import BEGIN, END, PERSIST
from physics_core.shapes import BOX, PLANE, SPHERE

from .shapes import rotation_matrix

from .camera import NEAR
from .geometry import box_faces, clip_near, clip_segment_near, plane_patch, sphere_silhouette

BACKGROUND = (0.965, 0.97, 0.975)
GROUND_RGB = (0.84, 0.85, 0.83)
GRID_RGBA = (0.55, 0.56, 0.55, 0.55)
SPRING_RGB = (0.30, 0.30, 0.34)
SHADOW_RGBA = (0.25, 0.25, 0.28, 0.22)
EVENT_RGB = {BEGIN: (0.10, 0.75, 0.15), PERSIST: (0.90, 0.72, 0.05), END: (0.85, 0.10, 0.10)}
EVENT_NAMES = {BEGIN: "begin", PERSIST: "persist", END: "end"}
NORMAL_LENGTH = 0.15  # m, as the node's contact arrows (msg_adapters.markers)
# Light from above, behind the viewer's left shoulder (camera axes: x right, y up, z forward).
_LIGHT_CAMERA = np.array([-0.35, 0.75, -0.55]) / np.linalg.norm([-0.35, 0.75, -0.55])
AMBIENT = 0.45
HIGHLIGHT = 0.35  # a sphere's highlight: this much of the way to white


def shade(rgb, normal, camera):
    """Lambert shading with the camera-fixed light: ambient + diffuse (n·l)."""
    light = camera.rotation.T @ _LIGHT_CAMERA
    k = AMBIENT + (1.0 - AMBIENT) * max(0.0, float(np.asarray(normal) @ light))
    return tuple(min(1.0, c * k) for c in rgb)


def sphere_fill(rgb):
    """The flat colour of a sphere's disc and of its highlight."""
    body = tuple(c * 0.9 for c in rgb)
    return body, tuple(c + HIGHLIGHT * (1.0 - c) for c in body)


def _attachment(frame, body, point):
    if body < 0:
        return np.asarray(point, dtype=np.float64)
    return frame.pos[body] + rotation_matrix(frame.quat[body]) @ point


def _coil(p, q, turns=10, radius=0.025, points_per_turn=12):
    """A helix from p to q (straight leads at both ends), as (k, 3) points."""
    axis = q - p
    length = float(np.linalg.norm(axis))
    if length < 1e-9:
        return np.array([p, q])
    axis /= length
    a = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(axis, a)
    s = np.linspace(0.1, 0.9, turns * points_per_turn + 1)
    phi = 2.0 * np.pi * turns * (s - 0.1) / 0.8
    helix = p + length * s[:, None] * axis + radius * (np.cos(phi)[:, None] * a + np.sin(phi)[:, None] * b)
    return np.vstack([p, helix, q])


class Renderer:
    def __init__(self, camera, shadows=True, legend=True, title=""):
        self.camera = camera
        self.shadows = shadows
        self.legend = legend
        self.title = title
        self.figure = Figure(figsize=(camera.width / 100.0, camera.height / 100.0), dpi=100)
        self.canvas = FigureCanvasAgg(self.figure)
        ax = self.figure.add_axes((0.0, 0.0, 1.0, 1.0))
        ax.set_xlim(0, camera.width)
        ax.set_ylim(camera.height, 0)
        ax.set_axis_off()
        ax.set_facecolor(BACKGROUND)
        self.figure.set_facecolor(BACKGROUND)
        self.ax = ax
        self._artists = []

    # -- one frame -------------------------------------------------------------
    def render(self, frame):
        """(height, width, 3) uint8 RGB picture of the frame."""
        for a in self._artists:
            a.remove()
        ground, grid = self._planes(frame)
        pieces = (self._shadows(frame) if self.shadows else []) + self._bodies(frame)
        self._artists = [
            self._polygons(ground, zorder=0.4),
            self.ax.add_collection(LineCollection(grid, colors=[GRID_RGBA], linewidths=0.6, zorder=0.5)),
            self._polygons(pieces, zorder=1),
            self.ax.add_collection(LineCollection(self._springs(frame), colors=[SPRING_RGB], linewidths=1.0,
                                                  zorder=2)),
            *self._contacts(frame),
            *self._hud(frame),
        ]
        self.canvas.draw()
        return np.asarray(self.canvas.buffer_rgba())[..., :3].copy()

    def _polygons(self, pieces, zorder):
        """One collection, drawn in list order: [(pixel polygon, face rgba, edge rgba, line width)]."""
        polys = [p[0] for p in pieces]
        collection = PolyCollection(
            polys,
            facecolors=[p[1] for p in pieces] or "none",
            edgecolors=[p[2] for p in pieces] or "none",
            linewidths=[p[3] for p in pieces] or 0.0,
            zorder=zorder,
            antialiaseds=True,
        )
        return self.ax.add_collection(collection)

    def _project_polygon(self, world_points):
        cam = clip_near(self.camera.to_camera(world_points))
        return None if cam is None else self.camera.to_pixels(cam)

    # -- what is drawn -------------------------------------------------------
    def _planes(self, frame):
        """Each plane as a square patch around the view's target, with a grid."""
        s, cam = frame.shapes, self.camera
        half = max(2.0, 1.5 * cam.distance)
        pieces, grid = [], []
        for i in np.flatnonzero(s.kind == PLANE):
            corners, segments = plane_patch(s.plane_normal[i], s.plane_offset[i], cam.target, half)
            poly = self._project_polygon(corners)
            if poly is not None:
                pieces.append((poly, GROUND_RGB + (1.0,), "none", 0.0))
            for p, q in cam.to_camera(segments):
                clipped = clip_segment_near(p, q)
                if clipped is not None:
                    grid.append(cam.to_pixels(np.array(clipped)))
        return pieces, grid

    def _shadows(self, frame):
        """A soft blob under each body on each plane it is above: the body's
        bounding circle dropped along the plane's normal."""
        s, pieces = frame.shapes, []
        planes = np.flatnonzero(s.kind == PLANE)
        phi = np.linspace(0.0, 2.0 * np.pi, 32, endpoint=False)
        for i in np.flatnonzero(s.kind != PLANE):
            r = s.bounding_radius(i) * (1.0 if s.kind[i] == SPHERE else 0.8)
            for j in planes:
                n, height = s.plane_normal[j], float(s.plane_normal[j] @ frame.pos[i] - s.plane_offset[j])
                if height < 0.0:
                    continue
                foot = frame.pos[i] - height * n + 1e-3 * n
                a = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
                a /= np.linalg.norm(a)
                b = np.cross(n, a)
                fade = 1.0 / (1.0 + 2.0 * height)
                ring = foot + r * (np.cos(phi)[:, None] * a + np.sin(phi)[:, None] * b)
                poly = self._project_polygon(ring)
                if poly is not None:
                    pieces.append((poly, SHADOW_RGBA[:3] + (SHADOW_RGBA[3] * fade,), "none", 0.0))
        return pieces

    def _bodies(self, frame):
        """Spheres and boxes, farthest first."""
        s, cam = frame.shapes, self.camera
        solid = np.flatnonzero(s.kind != PLANE)
        depth = cam.to_camera(frame.pos[solid])[:, 2] if len(solid) else np.zeros(0)
        pieces = []
        for i in solid[np.argsort(-depth, kind="stable")]:
            if s.kind[i] == SPHERE:
                pieces += self._sphere(frame.pos[i], float(s.radius[i]), s.color(i))
            elif s.kind[i] == BOX:
                pieces += self._box(frame.pos[i], frame.quat[i], s.half_extents[i], s.color(i))
        return pieces

    def _sphere(self, centre, radius, rgb):
        ring = sphere_silhouette(self.camera, centre, radius)
        if ring is None:
            return []
        poly = self._project_polygon(ring)
        if poly is None:
            return []
        body, light = sphere_fill(rgb)
        edge = tuple(c * 0.55 for c in rgb) + (1.0,)
        out = [(poly, body + (1.0,), edge, 0.8)]
        # A highlight towards the light: the silhouette shrunk to 40 % about a point 35 % of the way out.
        centre_px, toward = poly.mean(axis=0), np.array([_LIGHT_CAMERA[0], -_LIGHT_CAMERA[1]])
        size = 0.5 * float(np.ptp(poly[:, 0]))
        spot = centre_px + 0.35 * size * toward / np.linalg.norm(toward)
        out.append((spot + 0.4 * (poly - centre_px), light + (1.0,), "none", 0.0))
        return out

    def _box(self, pos, quat, half_extents, rgb):
        eye = self.camera.eye
        faces = []
        for corners, normal in box_faces(pos, quat, half_extents):
            if normal @ (eye - corners.mean(axis=0)) <= 0.0:
                continue  # facing away
            poly = self._project_polygon(corners)
            if poly is not None:
                edge = tuple(c * 0.5 for c in rgb) + (1.0,)
                faces.append((poly, shade(rgb, normal, self.camera) + (1.0,), edge, 0.7))
        return faces

    def _springs(self, frame):
        """Each spring as a coil between its attachment points (world frame)."""
        out = []
        for a, b, point_a, point_b in frame.shapes.springs:
            p = _attachment(frame, a, point_a)
            q = _attachment(frame, b, point_b)
            coil = _coil(p, q)
            cam = self.camera.to_camera(coil)
            if np.all(cam[:, 2] >= NEAR):
                out.append(self.camera.to_pixels(cam))
        return out

    def _contacts(self, frame):
        """Each event's point and its normal (from body a towards body b), coloured by event."""
        if len(frame.contact_event) == 0:
            return []
        cam = self.camera
        start = frame.contact_point
        end = start + NORMAL_LENGTH * frame.contact_normal
        colors = [EVENT_RGB.get(int(e), EVENT_RGB[PERSIST]) for e in frame.contact_event]
        segments, seg_colors = [], []
        for p, q, c in zip(cam.to_camera(start), cam.to_camera(end), colors):
            clipped = clip_segment_near(p, q)
            if clipped is not None:
                segments.append(cam.to_pixels(np.array(clipped)))
                seg_colors.append(c)
        dots = cam.project(start)
        shown = np.all(np.isfinite(dots), axis=1)
        return [
            self.ax.add_collection(LineCollection(segments, colors=seg_colors, linewidths=1.6, zorder=4)),
            self.ax.scatter(dots[shown, 0], dots[shown, 1], s=14, c=[c for c, k in zip(colors, shown) if k],
                            edgecolors="black", linewidths=0.4, zorder=5),
        ]

    def _hud(self, frame):
        """Sim time in the top-left corner, the event colours in the bottom-left."""
        h = self.camera.height
        size = max(7.0, h / 40.0)
        text = f"t = {frame.sim_time:.3f} s"
        if frame.part:
            text += f"  (after reset {frame.part}; playback {frame.time:.3f} s)"
        out = [self.ax.text(8, 8, text, fontsize=size, family="monospace", va="top", ha="left", zorder=6)]
        if self.title:
            out.append(self.ax.text(self.camera.width - 8, 8, self.title, fontsize=size * 0.9, va="top",
                                    ha="right", color=(0.3, 0.3, 0.3), zorder=6))
        if self.legend:
            x = 8.0
            for event in (BEGIN, PERSIST, END):
                out.append(self.ax.scatter([x + 4], [h - 12], s=16, c=[EVENT_RGB[event]], edgecolors="black",
                                           linewidths=0.4, zorder=6))
                label = self.ax.text(x + 11, h - 12, EVENT_NAMES[event], fontsize=size * 0.85, va="center",
                                     ha="left", color=(0.25, 0.25, 0.25), zorder=6)
                out.append(label)
                x += 11 + size * 0.85 * 0.62 * (len(EVENT_NAMES[event]) + 2) * 1.39
        return out
