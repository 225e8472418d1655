"""The Fast DDS profile the node's processes start with, so no service reply
is lost while the caller is still being discovered."""

import os

# Fast DDS 2.x reads the first name, Fast DDS 3.x the second; both are set so
# the profile is found whichever one the installed middleware is.
PROFILE_VARIABLES = ("FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE")
# The rmw implementations built on Fast DDS; an unset or empty
# RMW_IMPLEMENTATION means the ROS 2 default, which is Fast DDS.
FAST_DDS_RMWS = ("", "rmw_fastrtps_cpp", "rmw_fastrtps_dynamic_cpp")


def reply_profile_path():
    """The profiles file shipped inside the package (package data)."""
    return os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "fastdds_services.xml")


def use_reply_profile(environ=os.environ):
    """Give every service reply up to 5 s, instead of 100 ms, to find the
    caller; returns whether the profile was put in place.

    Before answering, a service waits until its reply can reach the caller
    (Fast DDS has matched the caller's reply reader), but by default only
    100 ms. A client may call as soon as it sees the service, before the
    service has seen the client; on a loaded machine that discovery takes
    longer than 100 ms, the first reply is dropped ("failed to send response
    (timeout)") and the caller waits forever. The shipped profile raises that
    wait to 5 s for service replies only; topics keep their QoS.

    Nothing is changed when the user has a profiles file of their own (it is
    used untouched) or the middleware is not Fast DDS. Call before
    rclpy.init: Fast DDS reads the variables when the first participant is
    made, and child processes inherit them.
    """
    if any(environ.get(name) for name in PROFILE_VARIABLES):
        return False
    if environ.get("RMW_IMPLEMENTATION", "") not in FAST_DDS_RMWS:
        return False
    for name in PROFILE_VARIABLES:
        environ[name] = reply_profile_path()
    return True
