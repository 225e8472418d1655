"""`physics-render`: pictures and video of a scene or a recording.

The world is drawn by this package's own pinhole camera (`camera.py`) onto a
matplotlib Agg canvas in pixel coordinates, so where a body lands on the
picture is a formula a test can check (`Camera.project`).
"""

from .camera import Camera, frame_scene
from .timeline import Frame, Shapes

__all__ = ["Camera", "Frame", "Shapes", "frame_scene"]
