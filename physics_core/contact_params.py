"""Settings of the `contacts` effect: collision detection and response."""
from dataclasses import dataclass


@dataclass(frozen=True)
class ContactParams:
    iterations: int = 8                 # velocity-solver iterations per (sub)step
    ccd: bool = True                    # time-of-impact bisection for fast bodies
    sleep: bool = True                  # freeze bodies at rest until touched or commanded


CONTACT_KEYS = {"iterations", "ccd", "sleep"}


def parse_contacts(r) -> ContactParams:
    """Read `effects.contacts` from a validate.Reader."""
    r.only(CONTACT_KEYS)
    d = ContactParams()
    return ContactParams(
        iterations=r.number("iterations", d.iterations, min=1, integer=True),
        ccd=r.boolean("ccd", d.ccd),
        sleep=r.boolean("sleep", d.sleep),
    )
