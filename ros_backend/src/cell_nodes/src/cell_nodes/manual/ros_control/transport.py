"""The rospy side of the ros_control backend: the arm's own driver's standard interfaces (docs/ros-interfaces.md,
"Any ROS arm"). Thin on purpose: arm.py decides, this only moves messages.

- <joint_states>: sensor_msgs/JointState (latest kept);
- <controller>/follow_joint_trajectory: control_msgs/FollowJointTrajectory (actionlib); the controller counts as
  running while its action server's status arrives (actionlib servers publish it at 5 Hz) and its goal topic is
  connected;
- <controller>/command: trajectory_msgs/JointTrajectory (jog stream; an empty one makes the controller hold);
- io: std_srvs/SetBool per output, std_msgs/Bool per input;
- the URDF from a parameter or a file.
"""
from __future__ import annotations

import os
import threading
import time
from typing import Callable, Optional, Sequence

import actionlib
import rospy
from actionlib.action_client import ClientGoalHandle, CommState
from actionlib_msgs.msg import GoalStatusArray
from control_msgs.msg import FollowJointTrajectoryAction, FollowJointTrajectoryGoal, JointTolerance
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool
from std_srvs.srv import SetBool
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from ...said import say
from ..config import RosControlSpec
from ..driver import Refused
from . import trajectory
from .arm import JointSample, Unreachable

STATUS_TIMEOUT = 1.0    # s without the action server's status: the controller is not running
SERVICE_TIMEOUT = 0.5   # s to find an IO service


class RosTransport:
    def __init__(self, spec: RosControlSpec, cell_dir: str = ".", joints: Sequence[str] = ()) -> None:
        self.spec = spec
        self._ours = frozenset(joints)  # other arms' drivers may publish on the same topic (often /joint_states)
        self.cell_dir = cell_dir
        self._joint: Optional[JointSample] = None
        self._status_at = -1e9
        self._inputs: dict[int, bool] = {}
        self._lock = threading.Lock()
        # Not SimpleActionClient: it takes a goal's transitions as its own only once send_goal has returned, and drops
        # the rest ("a goal handle that we're not tracking"); a short move's result can arrive before that, and the
        # move then never ended. Here each goal's callback is bound to that goal.
        self._client = actionlib.ActionClient(spec.action, FollowJointTrajectoryAction)
        self._goal: Optional[ClientGoalHandle] = None  # the client tracks a goal only while its handle lives
        self._command = rospy.Publisher(spec.command, JointTrajectory, queue_size=1)
        self._subs = [rospy.Subscriber(spec.joint_states, JointState, self._on_joints, queue_size=1, tcp_nodelay=True),
                      rospy.Subscriber(f"{spec.action}/status", GoalStatusArray, self._on_status, queue_size=1)]
        for n, topic in spec.inputs.items():
            self._subs.append(rospy.Subscriber(topic, Bool, lambda m, n=n: self._on_input(n, m), queue_size=1))
        self._outputs = {n: rospy.ServiceProxy(name, SetBool) for n, name in spec.outputs.items()}

    # ---- subscriptions
    def _on_joints(self, msg: JointState) -> None:
        if self._ours and self._ours.isdisjoint(msg.name):
            return  # another arm's message
        self._joint = JointSample(tuple(msg.name), tuple(msg.position), tuple(msg.velocity), time.monotonic())

    def _on_status(self, _msg: GoalStatusArray) -> None:
        self._status_at = time.monotonic()

    def _on_input(self, n: int, msg: Bool) -> None:
        self._inputs[n] = bool(msg.data)

    # ---- Transport
    def joint_state(self) -> Optional[JointSample]:
        return self._joint

    def controller_ready(self) -> bool:
        return time.monotonic() - self._status_at < STATUS_TIMEOUT and self._client.wait_for_server(
            rospy.Duration(0.05))

    def send_goal(self, names: Sequence[str], points: Sequence[trajectory.TrajectoryPoint], path_tolerance: float,
                  goal_time_tolerance: float, done: Callable[[int, int, str], None]) -> None:
        goal = FollowJointTrajectoryGoal()
        goal.trajectory.joint_names = list(names)
        goal.trajectory.points = [JointTrajectoryPoint(positions=list(p.positions), velocities=list(p.velocities),
                                                       time_from_start=rospy.Duration.from_sec(p.time_from_start))
                                  for p in points]
        goal.path_tolerance = [JointTolerance(name=n, position=path_tolerance) for n in names]
        goal.goal_time_tolerance = rospy.Duration.from_sec(goal_time_tolerance)

        def on_transition(gh: ClientGoalHandle) -> None:
            if gh.get_comm_state() != CommState.DONE:  # (DONE comes once: the goal's state machine stops there)
                return
            result = gh.get_result()
            code = int(getattr(result, "error_code", 0) or 0)
            done(int(gh.get_goal_status()), code, str(getattr(result, "error_string", "") or ""))

        self._goal = self._client.send_goal(goal, transition_cb=on_transition)

    def cancel_goal(self) -> None:
        self._client.cancel_all_goals()

    def stream(self, names: Sequence[str], point: trajectory.TrajectoryPoint) -> None:
        msg = JointTrajectory(joint_names=list(names))
        # Stamped, not 0 ("when it arrives"): the jog stream models the controller's setpoint on its own clock, and
        # a message's transit time varying by a few ms would otherwise make the setpoint run fast for a moment.
        msg.header.stamp = rospy.Time.now()
        msg.points = [JointTrajectoryPoint(positions=list(point.positions), velocities=list(point.velocities),
                                           time_from_start=rospy.Duration.from_sec(point.time_from_start))]
        self._command.publish(msg)

    def hold(self) -> None:
        self._command.publish(JointTrajectory(joint_names=[]))  # no points: hold the current position

    def set_output(self, output: int, value: bool) -> None:
        name = self.spec.outputs[output]
        proxy = self._outputs[output]
        try:
            proxy.wait_for_service(SERVICE_TIMEOUT)
            answer = proxy(value)
        except (rospy.ROSException, rospy.ServiceException) as e:
            raise Refused(say("manual.output_no_answer", "digital output {output}: the service {service} does not "
                              "answer ({error})", output=output, service=name, error=e))
        if not answer.success:
            raise Refused(say("manual.output_refused_by", "digital output {output}: {service} refused: {why}",
                              output=output, service=name, why=answer.message or "no reason given"))

    def inputs(self) -> dict[int, bool]:
        return dict(self._inputs)

    def robot_description(self) -> str:
        if self.spec.urdf:
            path = self.spec.urdf if os.path.isabs(self.spec.urdf) else os.path.join(self.cell_dir, self.spec.urdf)
            try:
                with open(path, encoding="utf-8") as f:
                    return f.read()
            except OSError as e:
                raise Unreachable(f"the URDF file {path} cannot be read: {e.strerror}")
        try:
            text = rospy.get_param(self.spec.robot_description or "/robot_description")
        except KeyError:
            raise Unreachable(f"no URDF on the parameter {self.spec.robot_description} (is the arm's driver up?)")
        if not isinstance(text, str):
            raise Unreachable(f"the parameter {self.spec.robot_description} is no URDF text")
        return text

    def close(self) -> None:
        for s in self._subs:
            s.unregister()
        self._command.unregister()
