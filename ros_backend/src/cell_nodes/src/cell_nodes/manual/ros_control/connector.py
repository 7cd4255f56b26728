"""The ros_control backend's Connector (controller.Connector): what driver.ManualDriver connects through. One
transport for the arm's life (its subscriptions survive reconnects); each connect loads the URDF again and checks
that the arm's driver publishes the group's joints, so a fixed URDF or a restarted driver is picked up by the
driver's normal retry."""
from __future__ import annotations

import time
from typing import Callable, Sequence

from ..config import RosControlSpec
from .arm import STATE_TIMEOUT, RosControlArm, Transport, Unreachable, load_kinematics

# s to wait at connect for the trajectory controller once the joint states are there: its action server's status
# comes at 5 Hz and the action client connects a moment after the joint states subscription. 3 s: on a loaded
# 2-core CI host, after the driver's process was frozen and let go, 1 s once passed before its status came (a
# CONTROLLER_NOT_RUNNING blip, an error alarm). A controller that really is not running is reported after it.
CONTROLLER_TIMEOUT = 3.0


class RosControlConnector:
    control_takes_over = False  # the control client is the same arm object: making it starts nothing

    def __init__(self, spec: RosControlSpec, joints: Sequence[str], transport: Transport, max_joint_speed: float,
                 state_timeout: float = STATE_TIMEOUT, sleep: Callable[[float], None] = time.sleep,
                 controller_timeout: float = CONTROLLER_TIMEOUT) -> None:
        self.spec = spec
        self.joints = tuple(joints)
        self.transport = transport
        self.max_joint_speed = max_joint_speed
        self.state_timeout = state_timeout
        self.controller_timeout = controller_timeout
        self.sleep = sleep
        self._arm: RosControlArm | None = None

    def receive(self, host: str) -> RosControlArm:
        kin = load_kinematics(self.spec, self.joints, self.transport.robot_description())
        arm = RosControlArm(self.spec, self.joints, self.transport, kin, self.max_joint_speed)
        deadline = time.monotonic() + self.state_timeout
        while not arm.isConnected():
            if time.monotonic() > deadline:
                raise Unreachable(f"no joint states on {self.spec.joint_states} (is the arm's driver running?)")
            self.sleep(0.02)
        arm.sample()  # raises when the group's joints are not all there
        # Connected with the controller's state known: else the first states after every (re)connect would say
        # CONTROLLER_NOT_RUNNING for a moment (an error alarm, and the cell's mode switched to alarm and back).
        # A controller that really is not running is reported so once this wait is over.
        deadline = time.monotonic() + self.controller_timeout
        while not self.transport.controller_ready() and time.monotonic() < deadline:
            self.sleep(0.02)
        self._arm = arm
        return arm

    def _current(self) -> RosControlArm:
        if self._arm is None:
            raise Unreachable("not connected")
        return self._arm

    def io(self, host: str) -> RosControlArm:
        return self._current()

    def control(self, host: str) -> RosControlArm:
        return self._current()

    def dashboard(self, host: str) -> RosControlArm:
        return self._current()
