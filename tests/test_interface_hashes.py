"""The interface packages built by `make install` (interfaces/build.py) are
the standard's types: their RIHS01 type hashes equal those of other Jazzy
builds, so this node talks to any tf2 or simulation_interfaces peer."""

import json
import sys
from pathlib import Path

import pytest
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

SHARE = Path(sys.prefix) / "share"
INTERFACES = Path(__file__).resolve().parent.parent / "interfaces"

# Hashes that an independent Jazzy build of simulation_interfaces 1.5.x
# generated (its GetEntitiesStates__description.c, found in public code):
# the service and every type it references.
THEIR_SIMULATION_HASHES = {
    "simulation_interfaces/srv/GetEntitiesStates": "0a76170d0c1c90e1eaf805cfab78ea801d1f82df309a28c1f0fae4b570f19754",
    "simulation_interfaces/srv/GetEntitiesStates_Request": "0af5302d3526834e83bd9861fbcc5214af2b9a4b0c93a965840fb1a6c2891724",
    "simulation_interfaces/srv/GetEntitiesStates_Response": "b651848f4d93a2b0ec5ec3f36659297ca30547c499f933eb279b60f8be434315",
    "simulation_interfaces/srv/GetEntitiesStates_Event": "3bfcf28a7087002f7f5be3539f5d069b660227c3f81e0e3195981e13a56d8b3d",
    "simulation_interfaces/msg/Bounds": "e8624fe51f0f5548197542697d924c5699ac7198f1e4c68e50c3ca2af73f5b3f",
    "simulation_interfaces/msg/EntityCategory": "43bdf7933fddf75f6970f7a8fe7078524355d821d390b3954bb46ac36c03dfe1",
    "simulation_interfaces/msg/EntityFilters": "8e7b12e8ea062f14c55de4877221fe1b7cd9749665a7ad8a4ab855fc4b148303",
    "simulation_interfaces/msg/EntityState": "2e0464a85eb80a939025075d6c20761eca6a4cb9d6baf2c0ba373467c8b598d0",
    "simulation_interfaces/msg/Result": "cf43a306adff3337a0a47143d8f5689933bc70a30478f13b077dc1fe3bc5ad17",
    "simulation_interfaces/msg/TagsFilter": "5c3efc51e8ed04c266c09cb4691ec95b964cd410558e01d8c83646b038826b45",
}


def built_hashes(package, kind, name):
    """{type name: RIHS01 string} that rosidl generated for one interface and
    everything it references (the hashes compiled into the libraries)."""
    path = SHARE / package / kind / f"{name}.json"
    data = json.loads(path.read_text())
    return {h["type_name"]: h["hash_string"] for h in data["type_hashes"]}


@pytest.mark.parametrize("name", ["TFMessage", "TF2Error"])
def test_tf2_msgs_hashes_equal_the_jazzy_type_store(name):
    store = get_typestore(Stores.ROS2_JAZZY)
    ours = built_hashes("tf2_msgs", "msg", name)[f"tf2_msgs/msg/{name}"]
    assert ours == store.hash_rihs01(f"tf2_msgs/msg/{name}")


def test_simulation_interfaces_hashes_equal_another_jazzy_build():
    ours = built_hashes("simulation_interfaces", "srv", "GetEntitiesStates")
    for type_name, theirs in THEIR_SIMULATION_HASHES.items():
        assert ours[type_name] == "RIHS01_" + theirs, type_name


def _simulation_msgs():
    return sorted(p.stem for p in (INTERFACES / "simulation_interfaces" / "msg").glob("*.msg"))


def test_every_simulation_message_hash_equals_rosbags_from_the_definitions():
    """rosbags hashes the definition text with its own implementation; the
    built types agree for all 15 messages (so the build dropped nothing)."""
    store = get_typestore(Stores.ROS2_JAZZY)
    names = _simulation_msgs()
    assert len(names) == 15
    types = {}
    for name in names:
        text = (INTERFACES / "simulation_interfaces" / "msg" / f"{name}.msg").read_text()
        types.update(get_types_from_msg(text, f"simulation_interfaces/msg/{name}"))
    store.register(types)
    for name in names:
        full = f"simulation_interfaces/msg/{name}"
        assert built_hashes("simulation_interfaces", "msg", name)[full] == store.hash_rihs01(full), name


def test_the_built_packages_hold_the_standards_interfaces():
    import simulation_interfaces.action as action
    import simulation_interfaces.srv as srv
    import tf2_msgs.msg as tf2

    assert [f for f in tf2.TFMessage.get_fields_and_field_types()] == ["transforms"]
    for name in ("SpawnEntity", "SpawnEntities", "DeleteEntity", "GetEntities", "GetEntityState", "SetEntityState",
                 "GetEntitiesStates", "GetEntityBounds", "GetEntityInfo", "StepSimulation", "ResetSimulation",
                 "GetSimulationState", "SetSimulationState", "GetSimulatorFeatures"):  # fmt: skip
        assert hasattr(srv, name), name
    assert srv.StepSimulation.Request().steps == 1  # the definition's default
    assert srv.SpawnEntity.Response.INVALID_POSE == 109
    assert hasattr(action, "SimulateSteps")
