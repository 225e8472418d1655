"""The node's recording: started with `--record FILE`, or at run time with
`ros2 param set /physics record FILE` (another file: the old one is closed
complete and the new one started; "": recording stops), and stopped by a
write error without stopping the simulation.

A path is checked by opening it when the parameter is set, as `--record`
checks it: a folder, a path whose folder cannot be made or an unwritable
file is refused with the reason and the node runs on (at start: exit 2).

A recording started mid-session is self-contained: the scene, the session
metadata (with the step it started at), the history since the last reset
(session_history.py: what `--resimulate` needs to rebuild the world up to
that step) and the latched messages as last sent (`~/bodies`, `/tf_static`,
`/clock`), so players and `physics-replay` see the world from its first step.
"""

import os

from .limits import excerpt
from .parameters import ParameterValueError
from .recorder import INTEGRATION_METADATA, SCENE_MEDIA_TYPE, SESSION_METADATA, Recorder, RecorderError, chunk_size_for
from .session import engine_version, integration_metadata, session_metadata
from .session_history import HISTORY_MEDIA_TYPE, HISTORY_NAME, HISTORY_STATE, STARTED_AT_STEP, SessionHistory


class RecordingControl:
    """The Recorder the node's outputs write to (or None), and the history
    every recording started later needs."""

    def __init__(self, node):
        self._node = node
        self.recorder = None
        self.error = ""  # why the last recording stopped early, until another starts
        self.history = SessionHistory(node.stepper)

    def open(self, path):
        """A Recorder open on `path`, not yet recorded to; ParameterValueError
        naming why it cannot be."""
        current = self.recorder
        if current is not None and os.path.realpath(current.path) == os.path.realpath(path):
            raise ParameterValueError(f"record: already recording to {path!r}")
        recorder = Recorder(
            path, chunk_size=chunk_size_for(len(self._node.world.model.names)),
            library=f"physics_node {engine_version()}",
        )
        try:
            return recorder.open()
        except OSError as exc:
            raise ParameterValueError(f"record: cannot write {path!r}: {exc.strerror or exc}") from None

    def start(self, recorder, mid_session=True):
        """Record into `recorder` (from `open`) from now on; the recording so
        far, if any, is closed complete first."""
        self.stop()
        node = self._node
        try:
            self._write_head(recorder, mid_session)
        except (RecorderError, OSError) as exc:
            self.recorder = recorder
            self.failed(exc)
            return
        self.recorder, self.error = recorder, ""
        node.outputs.set_recorder(recorder)
        if mid_session:
            node.outputs.record_latched(node.world.time, node.world.step_index)
        node.get_logger().info(f"recording to {recorder.path}" + (f" from step {node.world.step_index}" if mid_session else ""))

    def _write_head(self, recorder, mid_session):
        node = self._node
        name = os.path.basename(node.scene_path) or "scene.yaml"
        # the scene as loaded: --resimulate builds the world from it and re-applies the rest
        recorder.add_attachment(name, node.world.scene_model.source_text.encode(), SCENE_MEDIA_TYPE)
        values = session_metadata(node.settings, node.scene_path, node.world, node.get_fully_qualified_name())
        if mid_session:
            history = self.history.mcap()
            values[STARTED_AT_STEP] = str(node.world.step_index)
            values[HISTORY_STATE] = "complete" if history is not None else f"incomplete: {self.history.lost}"
            if history is not None:
                recorder.add_attachment(HISTORY_NAME, history, HISTORY_MEDIA_TYPE)
        recorder.add_metadata(SESSION_METADATA, values)

    def stop(self):
        """Close the recording, complete (integration totals, summary); the node runs on unrecorded."""
        recorder, self.recorder = self.recorder, None
        if recorder is None:
            return
        outputs = getattr(self._node, "outputs", None)
        if outputs is not None:
            outputs.set_recorder(None)
        try:
            stats = integration_metadata(self._node.world)
            if stats and recorder.is_open:
                recorder.add_metadata(INTEGRATION_METADATA, stats)
            recorder.close()
        except (RecorderError, OSError) as exc:
            self._fault(recorder, exc)

    def failed(self, exc):
        """A write failed (disk full, file-size limit, I/O error): the file is
        closed as far as it got; the simulation goes on unrecorded."""
        recorder, self.recorder = self.recorder, None
        if recorder is None:
            return
        self._node.outputs.set_recorder(None)
        try:
            recorder.close()  # the file ends with the last chunk written
        except (RecorderError, OSError):
            pass
        self._fault(recorder, exc)

    def _fault(self, recorder, exc):
        cause = exc.__cause__ or exc
        self.error = f"recording {recorder.path} stopped: {excerpt(cause, 300)}"
        self._node.get_logger().error(
            f"{self.error}; the simulation goes on unrecorded (`physics-replay {recorder.path} --recover OUT.mcap` "
            "reads what was written; `ros2 param set /physics record NEW.mcap` starts another recording)"
        )

    def add_attachment(self, name, data, media_type, time_ns):
        """A file the world read (a spawned body's), for --resimulate: kept in the history and recorded."""
        self.history.add_attachment(name, data, media_type, time_ns)
        if self.recorder is not None:
            try:
                self.recorder.add_attachment(name, data, media_type, time_ns)
            except (RecorderError, OSError) as exc:
                self.failed(exc)

    @property
    def path(self):
        return self.recorder.path if self.recorder is not None else ""
