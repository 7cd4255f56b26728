"""A FollowJointTrajectory action server for test_actions.py (ROS 2, a process of its own): it accepts a goal
unless it names no joint, sends one feedback per trajectory point, and succeeds once the points are done; a
joint named 'hold' keeps the goal running until it is canceled. Like a controller running a trajectory, it takes
time: 30 ms a point (rclpy's action client drops a feedback that arrives after the goal's result, and the two
travel on different channels)."""
import threading

import rclpy
from control_msgs.action import FollowJointTrajectory
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node


def main() -> None:
    rclpy.init()
    node = Node("test_fjt_server")

    def execute(goal_handle):  # type: ignore[no-untyped-def]
        goal = goal_handle.request
        tick = threading.Event()
        for point in goal.trajectory.points:
            fb = FollowJointTrajectory.Feedback()
            fb.joint_names = list(goal.trajectory.joint_names)
            fb.desired = point
            goal_handle.publish_feedback(fb)
            tick.wait(0.03)  # the point's execution time
        if "hold" in goal.trajectory.joint_names:
            while not goal_handle.is_cancel_requested:
                tick.wait(0.01)
            goal_handle.canceled()
            return FollowJointTrajectory.Result(error_code=0, error_string="canceled")
        goal_handle.succeed()
        return FollowJointTrajectory.Result(error_code=0, error_string=f"{len(goal.trajectory.points)} points")

    ActionServer(node, FollowJointTrajectory, "/test_arm/follow_joint_trajectory", execute_callback=execute,
                 goal_callback=lambda g: GoalResponse.ACCEPT if g.trajectory.joint_names else GoalResponse.REJECT,
                 cancel_callback=lambda _g: CancelResponse.ACCEPT, callback_group=ReentrantCallbackGroup())
    executor = MultiThreadedExecutor()
    executor.add_node(node)
    print("ready", flush=True)
    try:
        executor.spin()
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
