"""Every bound the node keeps on what peers send it, in one place (README,
"Limits and hostile input"). Past a bound the input is dropped and counted
with a reason, never queued without end; nothing here stops the simulation.

Command loads themselves are bounded in physics_core/command_limits.py.
"""

# Commands waiting for the next step boundary. A flood (or commands sent
# while paused) stops growing the queue at these bounds: the newest command
# is dropped as `queue_full`. Dropping the newest keeps what was queued in
# arrival order, so each peer's applied commands are a prefix of what it sent
# (a reliable stream's promise), and the check costs O(1) per command.
# Applying a command costs 50-130 us (10,000 impulses at one boundary took
# 1.3 s on this 2-core machine under load), so the total bound keeps the
# longest boundary, e.g. the first step after a paused flood, near 0.5 s.
MAX_QUEUED_PER_BODY = 1_000
MAX_QUEUED_TOTAL = 5_000

# Subscriptions that only count commands sent to bodies the scene lacks.
# At most this many topics are followed; more are not subscribed to (and so
# never reach the node); each one is let go of when its last publisher has
# been gone for UNKNOWN_TOPIC_EXPIRY_S. At most UNKNOWN_TOPICS_PER_SCAN new
# ones are made per graph scan, so discovering many peers is spread out.
MAX_UNKNOWN_BODY_TOPICS = 64
UNKNOWN_TOPIC_EXPIRY_S = 10.0
UNKNOWN_TOPICS_PER_SCAN = 8

# What the node keeps, recording or not, so that a recording started at run
# time re-simulates (session_history.py): the commands, requests, events and
# spawn files since the last full reset, each counted as its bytes plus
# HISTORY_ITEM_BYTES for what holds it. Past MAX_HISTORY_BYTES the history is
# dropped until the next reset; a recording started then plays back but
# does not re-simulate. 64 MiB holds about 300,000 commands (100 per second
# for 50 minutes).
MAX_HISTORY_BYTES = 64 << 20
HISTORY_ITEM_BYTES = 100

# Requests a service holds before the middleware drops the oldest; a burst
# of this many pause/unpause/reset calls is answered in order.
SERVICE_QUEUE_DEPTH = 1_000

# Longest log line built from what a peer sent (a frame_id, a body name);
# anything longer is cut and its length given.
LOG_TEXT_CHARS = 200


def excerpt(text, limit=LOG_TEXT_CHARS):
    """`text` cut to `limit` characters, saying how long it was."""
    text = str(text)
    if len(text) <= limit:
        return text
    return f"{text[:limit]}… ({len(text)} characters)"
