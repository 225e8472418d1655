"""What the world went through since it was last reset to its scene, so a
recording started mid-session (`ros2 param set /physics record new.mcap`)
can still be re-simulated bit for bit.

The engine is deterministic: the world at any step is the scene plus every
command, simulator request and event the node acted on since the last full
reset, each at its step. Those are the messages `--resimulate` reads from a
recording (commands on `~/<body>/wrench|impulse`, `~/requests/<service>`,
`~/events`, and the spawn files attached as read). The node keeps them here,
recording or not, and a new recording gets them as one attachment: an MCAP
file of its own (HISTORY_NAME, HISTORY_MEDIA_TYPE) that resimulate.py
re-applies before the recording's own messages. So the recording needs no
copy of the engine's internal state (contact warm starts, sleep timers, the
adaptive step controller), and readers that do not know the attachment
(rosbags, Foxglove, `physics-replay` playback) see an ordinary recording
that starts at the step it was started.

The history is bounded (limits.MAX_HISTORY_BYTES): past the bound it is
dropped and marked incomplete until the next full reset; a recording started
then says so in its metadata, plays back as usual, and `--resimulate`
refuses it with that reason.
"""

import io

from mcap.writer import CompressionType, Writer

from msg_adapters.schema import ros2msg_schema, type_name

from .limits import HISTORY_ITEM_BYTES, MAX_HISTORY_BYTES
from .qos import offered_qos_yaml
from .recorder import MESSAGE_ENCODING, PROFILE, SCHEMA_ENCODING

HISTORY_NAME = "history.mcap"
HISTORY_MEDIA_TYPE = "application/vnd.physics-node.history+mcap"
# Session metadata keys of a recording started mid-session.
STARTED_AT_STEP = "recording_started_step"
HISTORY_STATE = "history"  # "complete" or "incomplete: ..."


class SessionHistory:
    """Messages and attachments since the last full reset of `stepper`'s world."""

    def __init__(self, stepper, limit_bytes=MAX_HISTORY_BYTES):
        self._stepper = stepper
        self._limit = int(limit_bytes)
        self._resets = stepper.resets
        self._messages = []  # (topic, msg_class, data, time_ns, step, qos)
        self._attachments = []  # (name, data, media_type, time_ns)
        self.size = 0  # bytes counted against the bound
        self.lost = ""  # why the history is incomplete, if it is

    def _follow_resets(self):
        """A full reset makes the world its scene again: what came before is no longer needed."""
        if self._stepper.resets != self._resets:
            self._resets = self._stepper.resets
            self._messages, self._attachments, self.size, self.lost = [], [], 0, ""

    def _room(self, size, time_ns):
        self.size += size + HISTORY_ITEM_BYTES
        if self.size <= self._limit:
            return True
        if not self.lost:
            self.lost = (f"the node's history since the last reset passed {self._limit // (1 << 20)} MiB "
                         f"at sim time {time_ns / 1e9:.3f} s (physics_node/limits.py MAX_HISTORY_BYTES)")
            self._messages, self._attachments = [], []
        return False

    def add(self, topic, msg_class, data, time_ns, step, qos):
        """One message the node acted on (CDR bytes), at the step it took effect."""
        self._follow_resets()
        if not self.lost and self._room(len(data), time_ns):
            self._messages.append((topic, msg_class, bytes(data), int(time_ns), int(step), qos))

    def add_attachment(self, name, data, media_type, time_ns):
        self._follow_resets()
        if not self.lost and self._room(len(data), time_ns):
            self._attachments.append((name, bytes(data), media_type, int(time_ns)))

    @property
    def empty(self):
        self._follow_resets()
        return not self._messages and not self._attachments

    def mcap(self):
        """The history as the bytes of an MCAP file (ros2 profile, CDR), or
        None when it is incomplete."""
        self._follow_resets()
        if self.lost:
            return None
        out = io.BytesIO()
        writer = Writer(out, compression=CompressionType.ZSTD)
        writer.start(profile=PROFILE, library="physics_node history")
        for name, data, media_type, time_ns in self._attachments:
            writer.add_attachment(time_ns, time_ns, name, media_type, data)
        schemas, channels = {}, {}
        for topic, msg_class, data, time_ns, step, qos in self._messages:
            channel = channels.get(topic)
            if channel is None:
                name = type_name(msg_class)
                if name not in schemas:
                    schemas[name] = writer.register_schema(name, SCHEMA_ENCODING, ros2msg_schema(msg_class).encode())
                channel = channels[topic] = writer.register_channel(
                    topic, MESSAGE_ENCODING, schemas[name], {"offered_qos_profiles": offered_qos_yaml(qos)}
                )
            writer.add_message(channel, time_ns, data, time_ns, step)
        writer.finish()
        return out.getvalue()
