"""The rospy layer of one simulated ros_control arm: what iiwa_stack's driver offers over ROS, under the names of the
group's `manual.groups[].ros_control` section.

- joint_state_controller: sensor_msgs/JointState on <joint_states> at rate_hz (position, velocity, effort);
- joint_trajectory_controller (PositionJointInterface_trajectory_controller): the control_msgs/FollowJointTrajectory
  action server <controller>/follow_joint_trajectory and the topic <controller>/command (trajectory_msgs/
  JointTrajectory), with trajectory.py's semantics; invalid goals are rejected with their error code, as JTC does;
- the robot_description parameter: the URDF as simulated (model.py);
- the tool's IO: std_srvs/SetBool on the suction output's service, std_msgs/Bool "part held" on the input's topic.
Lock order: actionlib's own lock (held around its goal and cancel callbacks) before the cell's lock; never the other
way round, so goal handles are only touched outside the cell's lock (or in actionlib's callbacks).
"""
from __future__ import annotations

import logging
import queue
import threading

from ..pacing import Pacer
from . import model as mdl
from .trajectory import JointTolerance, Point

log = logging.getLogger("sim.ros_control.driver")

HOLDING_RATE = 20.0    # Hz, the "part held" input (the contract: >= 10 Hz)
FEEDBACK_RATE = 25.0   # Hz, action feedback (JTC's state_publish_rate)


class ArmDriver:
    def __init__(self, cell, rt) -> None:
        """`cell`: the RosControlCell (lock, sim_time, events, speed); `rt`: its ArmRuntime. rospy is initialised."""
        import actionlib
        import rospy
        from control_msgs.msg import (FollowJointTrajectoryAction, FollowJointTrajectoryFeedback,
                                      FollowJointTrajectoryResult)
        from sensor_msgs.msg import JointState
        from std_msgs.msg import Bool
        from std_srvs.srv import SetBool, SetBoolResponse
        from trajectory_msgs.msg import JointTrajectory

        self.rospy, self.cell, self.rt = rospy, cell, rt
        self.Result, self.Feedback, self.JointState, self.Bool = (FollowJointTrajectoryResult,
                                                                 FollowJointTrajectoryFeedback, JointState, Bool)
        self.SetBoolResponse = SetBoolResponse
        spec = rt.spec
        names = spec.ros
        self.joint_names = list(spec.model.joint_names)
        rospy.set_param(names.robot_description,
                        mdl.urdf_text(spec.model, spec.rename_map, names.tip_link, spec.tool_length, mesh_uri=True))
        # A second of joint states per subscriber: rospy drops the oldest when a connection's writer thread falls
        # behind, and on a starved host (two e2e lanes on two cores) 10 (50 ms at 200 Hz) lost some of them.
        self.pub_joints = rospy.Publisher(names.joint_states, JointState, queue_size=max(10, int(spec.rate_hz)))
        self.pub_holding = rospy.Publisher(names.holding_topic, Bool, queue_size=5)
        self.suction = rospy.Service(names.suction_service, SetBool, self._set_suction)
        self.server = actionlib.ActionServer(f"{names.controller}/follow_joint_trajectory", FollowJointTrajectoryAction,
                                             self._on_goal, self._on_cancel, auto_start=False)
        self.sub_command = rospy.Subscriber(f"{names.controller}/command", JointTrajectory, self._on_command,
                                            queue_size=10)
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []

    def start(self) -> None:
        self.server.start()
        for target, name in ((self._publish_loop, "joint-states"), (self._result_loop, "action-results")):
            t = threading.Thread(target=target, name=f"{name}-{self.rt.group}", daemon=True)
            t.start()
            self._threads.append(t)
        log.info("arm %s: %s/follow_joint_trajectory, %s at %g Hz", self.rt.group, self.rt.spec.ros.controller,
                 self.rt.spec.ros.joint_states, self.rt.spec.rate_hz)

    def stop(self) -> None:
        self._stop.set()
        for t in self._threads:
            t.join(0.5)
        # The server's status timer would otherwise publish on a topic rospy is closing (a traceback at exit).
        self.server.stop()
        self.sub_command.unregister()
        self.suction.shutdown("sim stopping")

    # ---- time ------------------------------------------------------------------------------------------
    def _start_time(self, stamp, now: float) -> float:
        """header.stamp (ROS time; 0 = now) as controller time (sim seconds)."""
        if stamp.is_zero():
            return now
        return now + (stamp.to_sec() - self.rospy.Time.now().to_sec()) * self.cell.opts.speed

    @staticmethod
    def _points(traj) -> list[Point]:
        return [Point(p.time_from_start.to_sec(), tuple(p.positions), tuple(p.velocities), tuple(p.accelerations))
                for p in traj.points]

    # ---- the action -------------------------------------------------------------------------------------
    def _on_goal(self, gh) -> None:
        goal = gh.get_goal()
        tr = goal.trajectory
        tols = [[JointTolerance(t.name, t.position, t.velocity, t.acceleration) for t in lst]
                for lst in (goal.path_tolerance, goal.goal_tolerance)]
        with self.cell.lock:
            now = self.cell.sim_time
            outcome = self.rt.ctl.submit_goal(gh, list(tr.joint_names), self._points(tr),
                                              self._start_time(tr.header.stamp, now), now, tols[0], tols[1],
                                              goal.goal_time_tolerance.to_sec(), q_actual=self.rt.snapshot.q)
        # Still inside actionlib's lock: the loop's result for this goal (results thread) waits for the accept.
        if not outcome.accepted:
            log.warning("arm %s: goal rejected (%d): %s", self.rt.group, outcome.code, outcome.text)
            gh.set_rejected(self.Result(error_code=outcome.code, error_string=outcome.text), outcome.text)
            return
        if outcome.preempted is not None:
            outcome.preempted.set_canceled(self.Result(), "preempted by a new goal")
        gh.set_accepted("")

    def _on_cancel(self, gh) -> None:
        with self.cell.lock:
            self.rt.ctl.cancel(gh, self.cell.sim_time, self.rt.snapshot.q)
        gh.set_canceled(self.Result(), "canceled")

    def _on_command(self, msg) -> None:
        with self.cell.lock:
            now = self.cell.sim_time
            outcome = self.rt.ctl.submit_command(list(msg.joint_names), self._points(msg),
                                                 self._start_time(msg.header.stamp, now), now, self.rt.snapshot.q)
        if not outcome.accepted:
            log.error("arm %s: command trajectory dropped (%d): %s", self.rt.group, outcome.code, outcome.text)
        if outcome.preempted is not None:  # outside the cell's lock: this takes actionlib's
            outcome.preempted.set_canceled(self.Result(), "preempted by a trajectory on the command topic")

    def _result_loop(self) -> None:
        """Goals the control loop ended (succeeded, tolerance aborts) get their result here, off the loop."""
        while not self._stop.is_set():
            try:
                ev = self.rt.events.get(timeout=0.1)
            except queue.Empty:
                continue
            result = self.Result(error_code=ev.code, error_string=ev.text)
            if ev.status == "succeeded":
                ev.goal.set_succeeded(result, ev.text)
            else:
                log.warning("arm %s: goal aborted (%d): %s", self.rt.group, ev.code, ev.text)
                ev.goal.set_aborted(result, ev.text)

    # ---- joint states, IO, feedback -------------------------------------------------------------------
    def _publish_loop(self) -> None:
        rate = self.rt.spec.rate_hz
        pacer = Pacer(1.0 / rate, self._stop)
        every_holding = max(1, round(rate / HOLDING_RATE))
        every_feedback = max(1, round(rate / FEEDBACK_RATE))
        k, last_holding = 0, None
        while not self._stop.is_set():
            try:
                snap = self.rt.snapshot
                js = self.JointState()
                js.header.stamp = self.rospy.Time.now()
                js.name = self.joint_names
                js.position, js.velocity, js.effort = list(snap.q), list(snap.qd), list(snap.effort)
                self.pub_joints.publish(js)
                if k % every_holding == 0 or snap.holding != last_holding:
                    self.pub_holding.publish(self.Bool(data=snap.holding))
                    last_holding = snap.holding
                if k % every_feedback == 0:
                    self._feedback(snap, js.header.stamp)
            except Exception:
                if self._stop.is_set():
                    return
                log.exception("publish failed")
            k += 1
            pacer.wait()

    def _feedback(self, snap, stamp) -> None:
        gh = self.rt.ctl.active_goal
        if gh is None:
            return
        q_des, qd_des, _ = self.rt.ctl.desired
        fb = self.Feedback()
        fb.header.stamp = stamp
        fb.joint_names = self.joint_names
        fb.desired.positions, fb.desired.velocities = list(q_des), list(qd_des)
        fb.actual.positions, fb.actual.velocities = list(snap.q), list(snap.qd)
        fb.error.positions = list(q_des - snap.q)
        fb.error.velocities = list(qd_des - snap.qd)
        gh.publish_feedback(fb)

    def _set_suction(self, req):
        with self.cell.lock:
            frozen = self.rt.body.gripper_frozen
            self.rt.body.set_suction(bool(req.data))
        # A real IO write succeeds whatever the device does; a vacuum fault only shows as no part held.
        return self.SetBoolResponse(success=True, message="suction on" if req.data else "suction off") if not frozen \
            else self.SetBoolResponse(success=True, message="written (the vacuum does not respond)")

