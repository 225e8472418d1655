"""What a recording says about the session that made it."""

import dataclasses
import json
from importlib import metadata

import physics_core

from .parameters import PARAMETERS


def engine_version():
    version = getattr(physics_core, "__version__", None)
    if version:
        return str(version)
    try:
        return metadata.version("physics_node")
    except metadata.PackageNotFoundError:
        return "unknown"


def session_metadata(settings, scene_path, world, node_name):
    """Key-value strings for the recording's `physics_node` metadata record.
    Parameter values are JSON so their types survive."""
    values = {f"param.{name}": json.dumps(getattr(settings, name)) for name in PARAMETERS}
    values.update(
        {
            "engine_version": engine_version(),
            "node": node_name,
            "scene_path": str(scene_path),
            "dt": repr(float(world.dt)),
            "integrator": str(world.model.integrator),
            "bodies": json.dumps(list(world.model.names)),
            "step_index": "mcap message sequence field",
            "log_time": "sim time of the step (commands: the step that applied them), ns",
        }
    )
    accuracy = getattr(world.model, "accuracy", None)
    if accuracy is not None:
        values["accuracy"] = json.dumps(dataclasses.asdict(accuracy))
    return values


def integration_metadata(world):
    """Key-value strings for the `physics_integration` metadata record written
    when an adaptive session's recording closes: World.integration_stats, totals
    over the session; {} for a fixed-step integrator."""
    return {name: repr(value) for name, value in (getattr(world, "integration_stats", {}) or {}).items()}
