"""Counting commands sent to bodies the scene lacks, with bounded cost.

The graph is scanned for command topics under the node (`~/<name>/wrench`,
`~/<name>/impulse`) whose body is not in the scene; each gets a subscription
that only drops and counts. Bounds (limits.py): at most
MAX_UNKNOWN_BODY_TOPICS such subscriptions, at most UNKNOWN_TOPICS_PER_SCAN
new ones per scan (so a thousand peers appearing at once are discovered over
several scans, not in one long pause of the step timer), and each is
destroyed once its topic has had no publisher for UNKNOWN_TOPIC_EXPIRY_S.
Topics beyond the cap are not subscribed to: their messages never reach the
node, and `unknown_body_topics_ignored` in /diagnostics counts the topics.
"""

import re
import time

from geometry_msgs.msg import WrenchStamped

from .commands import IMPULSE, UNKNOWN_BODY, WRENCH
from .limits import MAX_UNKNOWN_BODY_TOPICS, UNKNOWN_TOPIC_EXPIRY_S, UNKNOWN_TOPICS_PER_SCAN, excerpt
from .qos import COMMANDS, per_body_events


class UnknownBodyTopics:
    def __init__(self, node, names, on_drop):
        self._node = node
        self._names = frozenset(names)
        self._shown = _shown(names)
        self._on_drop = on_drop  # (topic, reason, detail) for each message received
        prefix = re.escape(node.get_fully_qualified_name())
        self._pattern = re.compile(rf"^{prefix}/([^/]+)/({WRENCH}|{IMPULSE})$")
        self.subscriptions = {}  # topic -> subscription
        self._idle_since = {}  # topic -> monotonic time its publishers were last seen gone
        self.ignored = set()  # topics seen beyond the cap

    def bodies_changed(self, names):
        """Bodies were spawned or deleted: a spawned body's topics are its own now."""
        self._names = frozenset(names)
        self._shown = _shown(names)
        for topic in [t for t in self.subscriptions if self._pattern.match(t).group(1) in names]:
            self._node.destroy_subscription(self.subscriptions.pop(topic))
            self._idle_since.pop(topic, None)

    def scan(self, now=None, topics=None):
        """One graph scan: expire idle subscriptions, subscribe to new topics.
        `topics`: the graph's (name, types) pairs, if already fetched."""
        now = time.monotonic() if now is None else now
        self._expire(now)
        made = 0
        for topic, _types in self._node.get_topic_names_and_types() if topics is None else topics:
            match = self._pattern.match(topic)
            if not match or match.group(1) in self._names or topic in self.subscriptions:
                continue
            if len(self.subscriptions) >= MAX_UNKNOWN_BODY_TOPICS:
                self.ignored.add(topic)
                continue
            if made >= UNKNOWN_TOPICS_PER_SCAN:
                break
            self._subscribe(topic, match.group(1))
            made += 1
        return made

    def _subscribe(self, topic, body):
        detail = f"no body named {excerpt(body, 60)!r}; bodies are {self._shown}"

        def on_unknown(_raw, topic=topic, detail=detail):
            self._on_drop(topic, UNKNOWN_BODY, detail)

        self.ignored.discard(topic)
        self.subscriptions[topic] = self._node.create_subscription(
            WrenchStamped, topic, on_unknown, COMMANDS, raw=True, event_callbacks=per_body_events()[1]
        )

    def _expire(self, now):
        for topic, sub in list(self.subscriptions.items()):
            if sub.get_publisher_count() > 0:
                self._idle_since.pop(topic, None)
                continue
            since = self._idle_since.setdefault(topic, now)
            if now - since >= UNKNOWN_TOPIC_EXPIRY_S:
                self._node.destroy_subscription(sub)
                del self.subscriptions[topic]
                del self._idle_since[topic]
        if len(self.subscriptions) < MAX_UNKNOWN_BODY_TOPICS:
            self.ignored.clear()  # re-examined at this scan


def _shown(names):
    """The first bodies' names, for a log line."""
    names = list(names)
    return ", ".join(names[:20]) + (f" and {len(names) - 20} more" if len(names) > 20 else "")
