"""At real_time_factor 0 the node steps as fast as it can and still answers
its services and commands (node.PhysicsNode._free_run)."""

import time

from test_node_support import FREE_SCENE, Driver, NodeProcess

from diagnostic_msgs.msg import DiagnosticArray
from rcl_interfaces.srv import GetParameters

from msg_adapters import diagnostic_values

RUN_S = 10.0          # the bug's wait had grown past 1.5 s by then
LONGEST_REPLY_S = 1.0  # about 20 ms here (one step budget); the rest for a loaded machine
FREE_DT = 0.01         # FREE_SCENE's dt


def test_service_calls_waited_longer_the_longer_the_node_ran_free(tmp_path):
    """Regression: at real_time_factor 0 the node stepped from a timer of
    period 0. Always due, it made rclpy's EventsExecutor queue timer events
    faster than it ran them, and a service call waited behind them: 1.6 s
    after 5 s of running, 2.4 s after 10 s, 24 s after 49 s (a recording
    test timed out after 50 s waiting for `set_parameters`). Each budget of
    steps is now a task queued behind what arrived meanwhile: after RUN_S of
    running free every call is answered within LONGEST_REPLY_S, and the
    node has kept stepping faster than real time."""
    scene = tmp_path / "free.yaml"
    scene.write_text(FREE_SCENE)
    request = GetParameters.Request(names=["real_time_factor"])
    with NodeProcess(["--scene", scene, "--rtf", "0"], tmp_path) as node, Driver("free_run") as driver:
        node.wait_until_up()
        driver.listen(DiagnosticArray, "/diagnostics")
        driver.call(GetParameters, "/physics/get_parameters", request=request)  # found, and answered once
        driver.spin_for(RUN_S)
        waits = []
        for _ in range(5):
            start = time.monotonic()
            driver.call(GetParameters, "/physics/get_parameters", request=request, timeout=10.0)
            waits.append(time.monotonic() - start)
            driver.spin_for(0.2)
        assert max(waits) < LONGEST_REPLY_S, waits
        assert node.alive(), node.log()[-3000:]
        steps = int(diagnostic_values(driver.received["/diagnostics"][-1])["steps"])
        assert steps * FREE_DT > RUN_S, steps
