"""Recorded simulator-standard requests, re-applied in `--resimulate`.

The node records each world-changing request as received on
`<node>/requests/<service>` at the step it took effect (sim_services.py);
here each is decoded and applied through the same `apply_request` and
`Entities` code, with a stand-in for the node's pause and output hooks
(pausing changes no state: the recorded steps drive the re-simulation).
"""

import collections

from rclpy.serialization import deserialize_message
from simulation_interfaces import srv
from simulation_interfaces.msg import SimulationState

from physics_core.scene_limits import MAX_BODIES

from .entities import Entities, EntityError, read_uri_file
from .sim_requests import CHANGING, REQUESTS_SUFFIX, SPAWN_ATTACHMENT_PREFIX, SPAWN_MEDIA_TYPE, apply_request

SERVICE_TYPES = {
    "spawn_entity": srv.SpawnEntity,
    "spawn_entities": srv.SpawnEntities,
    "delete_entity": srv.DeleteEntity,
    "set_entity_state": srv.SetEntityState,
    "reset_simulation": srv.ResetSimulation,
    "set_simulation_state": srv.SetSimulationState,
}
assert set(SERVICE_TYPES) == set(CHANGING)


class ReplayedRequests:
    """The context apply_request needs, without a node."""

    def __init__(self, stepper, node_name, attachments=(), max_bodies=MAX_BODIES):
        self._files = collections.defaultdict(collections.deque)  # uri -> texts, in the order read
        for a in attachments:
            if a.media_type == SPAWN_MEDIA_TYPE and a.name.startswith(SPAWN_ATTACHMENT_PREFIX):
                self._files[a.name[len(SPAWN_ATTACHMENT_PREFIX) :]].append(bytes(a.data).decode())
        self.entities = Entities(stepper, read_uri=self._recorded_file, max_bodies=max_bodies)
        self.stopped = False
        self.faulted = ""
        self._prefix = node_name + REQUESTS_SUFFIX + "/"

    def _recorded_file(self, uri):
        texts = self._files.get(uri)
        if texts:
            return texts.popleft()
        return read_uri_file(uri)  # not read when recorded (it failed then): the same error now

    def takes(self, topic):
        return topic.startswith(self._prefix) and topic[len(self._prefix) :] in SERVICE_TYPES

    def apply(self, topic, data):
        """Re-apply one recorded request; 1 (it counts as re-applied)."""
        kind = SERVICE_TYPES[topic[len(self._prefix) :]]
        request = deserialize_message(data, kind.Request)
        try:
            apply_request(self, topic[len(self._prefix) :], request, kind.Response())
        except EntityError:
            pass  # refused when recorded too: the same code refuses it again
        return 1

    def reset_all(self):
        """The Gazebo-classic Empty reset: as ResetSimulation SCOPE_ALL."""
        self.entities.reset(0)

    def stepped(self):
        self.stopped = False

    # -- hooks of apply_request ------------------------------------------------
    def simulation_state(self):
        return SimulationState.STATE_STOPPED if self.stopped else -1

    def set_paused(self, _paused):
        pass

    def after_reset(self, _state_cleared):
        pass

    def static_moved(self):
        pass

    def quit(self):
        pass
