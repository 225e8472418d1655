"""The contact stages of a World: built once per model, holding what they keep
between substeps (warm starts, sleep timers, the event log) as arrays that
compiled code reads and grows (contact_data.py).

`ContactSystem(model, params)`:
- `stage_names`: the stages in order, only those the parameters switch on;
- `args()`: what the compiled step loop passes to the contact stages
  (step_loop.py, contact_substep.run);
- `events()`: the last step's ContactEvents;
- `bodies_changed(...)`: the kept state renumbered after add/remove_body.
"""
import numpy as np

from .contact_data import contact_model, contact_params, new_sleep_state, new_warm_cache
from .contact_substep import STAGE_NAMES
from .event_log import events_bodies_changed, events_output, new_event_state
from .manifold import SLOTS
from .scratch import KEPT, new_counts, new_scratch
from .warm_cache import remap_warm_cache


class ContactSystem:
    def __init__(self, model, params):
        self.model = model
        self.params = params
        self.cm = contact_model(model)
        self.fp, self.ip = contact_params(params, model.integrator)
        names = list(STAGE_NAMES)
        if not params.sleep:
            names.remove("sleep")
        if not params.ccd:
            names.remove("ccd")
        self.stage_names = names
        self.stage_index = [i for i, name in enumerate(STAGE_NAMES) if name in names]
        self.reset()

    def reset(self):
        n = self.model.n
        self.warm = new_warm_cache()
        self.sleep = new_sleep_state(n)
        self.events_state = new_event_state()
        self.cap = new_counts()
        self.scratch = new_scratch()

    def args(self):
        """(contacts, warm cache, event state, scratch): step_loop.run_steps' arguments."""
        return ((self.cm, self.fp, self.ip, self.sleep, self.cap), self.warm, self.events_state,
                self.scratch)

    def events(self):
        return events_output(self.events_state)

    def bodies_changed(self, old, new_index):
        """Take over `old`'s kept state (another ContactSystem, of the model
        before the change) under the new numbering; sleep timers start afresh."""
        n_old, n_new = len(new_index), self.model.n
        self.warm = old.warm
        remap_warm_cache(self.warm[0], self.warm[1], n_old, n_new, new_index, SLOTS)
        self.events_state = old.events_state
        events_bodies_changed(self.events_state, n_old, n_new, new_index)
        self.cap = old.cap
        self.cap[KEPT] = -1             # the kept broad-phase pairs name the old bodies
        self.scratch = old.scratch      # grown as needed: any size serves



