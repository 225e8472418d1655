"""/tf and /tf_static: `world` → each body frame, child frame = body name.

Dynamic bodies go on /tf with every published step; static bodies on the
latched /tf_static, sent again whenever the body list changes (a latched
topic keeps only its last message, so each one holds every static body).
Both are stamped with sim time and built as CDR (msg_adapters.tf).
"""

import numpy as np

from msg_adapters.tf import TransformsCdr


class TfOutput:
    def __init__(self, dynamic_publisher, static_publisher, model):
        self.dynamic = dynamic_publisher
        self.static = static_publisher
        self.bodies_changed(model)

    def bodies_changed(self, model):
        static = np.asarray(model.is_static, dtype=bool)
        self._moving = np.flatnonzero(~static)
        self._fixed = np.flatnonzero(static)
        self._dynamic_cdr = TransformsCdr([model.names[i] for i in self._moving])
        self._static_cdr = TransformsCdr([model.names[i] for i in self._fixed])

    @property
    def has_dynamic(self):
        return len(self._moving) > 0

    def build(self, state, time_ns):
        """CDR of /tf for this step."""
        rows = self._moving
        return self._dynamic_cdr.build(state.pos[rows], state.quat[rows], time_ns)

    def build_static(self, state, time_ns):
        rows = self._fixed
        return self._static_cdr.build(state.pos[rows], state.quat[rows], time_ns)
