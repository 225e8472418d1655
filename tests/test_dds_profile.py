"""The Fast DDS profile that gives service replies 5 s, not 100 ms, to find
their caller: when it is put in place, what it holds, and that a service
still answers with it loaded."""

import re
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from physics_node.dds_profile import PROFILE_VARIABLES, reply_profile_path, use_reply_profile
from test_node_support import DEADLINE_SCALE, REPO, node_env

NS = "{http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles}"
# Fast DDS colours its log lines even into a pipe ("XMLPARSER\x1b[31;1m Error]").
ANSI = re.compile(r"\x1b\[[0-9;]*m")


def test_an_empty_environment_gets_both_variables_pointing_at_the_shipped_file():
    environ = {}
    assert use_reply_profile(environ) is True
    assert set(environ) == set(PROFILE_VARIABLES)
    assert len(set(environ.values())) == 1
    path = Path(environ["FASTRTPS_DEFAULT_PROFILES_FILE"])
    assert path.is_absolute() and path.is_file()


def test_the_file_declares_only_a_service_writer_blocking_up_to_5_s():
    root = ET.parse(reply_profile_path()).getroot()
    assert root.tag == "dds"
    [profiles] = list(root)
    assert profiles.tag == NS + "profiles"
    # Only the reply writers' profile: topics and everything else keep their QoS.
    [writer] = list(profiles)
    assert writer.tag == NS + "data_writer"
    assert writer.attrib == {"profile_name": "service"}
    [qos] = list(writer)
    [reliability] = list(qos)
    assert (qos.tag, reliability.tag) == (NS + "qos", NS + "reliability")
    [blocking] = list(reliability)
    assert blocking.tag == NS + "max_blocking_time"
    assert {child.tag: child.text for child in blocking} == {NS + "sec": "5"}


def test_a_users_own_profiles_file_is_left_alone():
    for name in PROFILE_VARIABLES:
        environ = {name: "/home/user/my_profiles.xml"}
        assert use_reply_profile(environ) is False
        assert environ == {name: "/home/user/my_profiles.xml"}


def test_another_middleware_gets_nothing_and_fast_dds_names_get_the_profile():
    environ = {"RMW_IMPLEMENTATION": "rmw_cyclonedds_cpp"}
    assert use_reply_profile(environ) is False
    assert environ == {"RMW_IMPLEMENTATION": "rmw_cyclonedds_cpp"}
    for rmw in ("", "rmw_fastrtps_cpp", "rmw_fastrtps_dynamic_cpp"):
        assert use_reply_profile({"RMW_IMPLEMENTATION": rmw}) is True


# One node serves a service and calls it, in a process that put the profile in
# place itself before rclpy.init (as physics-node does). rcl_interfaces is in
# every ROS install, so no extra interface package is needed.
SERVE_AND_CALL = """
import time
from physics_node.dds_profile import use_reply_profile
assert use_reply_profile()
import rclpy
from rcl_interfaces.msg import ParameterValue
from rcl_interfaces.srv import GetParameters

def answer(request, response):
    response.values = [ParameterValue(type=4, string_value="pong " + request.names[0])]
    return response

rclpy.init()
node = rclpy.create_node("reply_profile_probe")
node.create_service(GetParameters, "~/probe", answer)
client = node.create_client(GetParameters, "~/probe")
start = time.monotonic()
while not client.service_is_ready() and time.monotonic() - start < 10:
    rclpy.spin_once(node, timeout_sec=0.05)
future = client.call_async(GetParameters.Request(names=["ping"]))
rclpy.spin_until_future_complete(node, future, timeout_sec=10)
print("reply:", future.result().values[0].string_value if future.done() else None,
      round(time.monotonic() - start, 2), flush=True)
node.destroy_node()
rclpy.shutdown()
"""


def _run_ros(program, **variables):
    """(stdout, stderr without colours) of `python -c program` on Fast DDS,
    with no profiles file set but `variables`."""
    env = node_env()
    for name in PROFILE_VARIABLES:
        env.pop(name, None)
    env.update(variables, RMW_IMPLEMENTATION="rmw_fastrtps_cpp")
    run = subprocess.run([sys.executable, "-c", program], cwd=REPO, env=env,
                         capture_output=True, text=True, timeout=30 * DEADLINE_SCALE)
    assert run.returncode == 0, run.stderr
    return run.stdout, ANSI.sub("", run.stderr)


def test_a_service_answers_with_the_profile_loaded_and_no_parser_error():
    out, err = _run_ros(SERVE_AND_CALL)
    words = out.split()
    assert words[:3] == ["reply:", "pong", "ping"], out + err
    assert float(words[3]) < 10.0
    assert "XMLPARSER Error" not in err
    assert "failed to send response" not in err


# The reply writer's max_blocking_time cannot be read from outside, but its
# deadline shows in the ROS graph: the shipped profile with a 7 s deadline
# added shows that rmw_fastrtps gives this profile to a service's reply
# writer, and to nothing else of the service.
SHOW_DEADLINES = """
import rclpy
from rcl_interfaces.srv import GetParameters
rclpy.init()
node = rclpy.create_node("reply_profile_graph")
node.create_service(GetParameters, "/reply_profile_probe", lambda request, response: response)
writers = node.get_publishers_info_by_topic("rr/reply_profile_probeReply", no_mangle=True)
readers = node.get_subscriptions_info_by_topic("rq/reply_profile_probeRequest", no_mangle=True)
print(*[i.qos_profile.deadline.nanoseconds for i in writers])
print(*[i.qos_profile.deadline.nanoseconds for i in readers])
"""


def test_the_profile_reaches_the_reply_writer_only(tmp_path):
    text = Path(reply_profile_path()).read_text()
    marked = tmp_path / "marked.xml"
    deadline = "<deadline><period><sec>7</sec></period></deadline>"
    marked.write_text(text.replace("</reliability>", "</reliability>" + deadline))
    out, err = _run_ros(SHOW_DEADLINES, FASTRTPS_DEFAULT_PROFILES_FILE=str(marked))
    writers, readers = out.splitlines()
    assert writers == "7000000000", out + err
    assert readers and "7000000000" not in readers, out
    assert "XMLPARSER Error" not in err
