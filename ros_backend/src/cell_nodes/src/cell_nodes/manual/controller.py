"""The robot controller as the driver sees it: ur_rtde's three interfaces behind small protocols (so tests use a
fake, and the node the real `rtde_control`, `rtde_receive`, `rtde_io` modules in a child process: ur_process), UR
mode names, and the gate every call goes through.

Why a gate: ur_rtde's clients are not thread-safe, so every call takes one lock; and a control call made while the
controller vanishes can block forever (seen with speedStop after the controller died: it never returned). The gate
therefore runs each call on a worker thread and waits with a timeout: a call that does not come back costs the
caller CallTimeout (the driver then treats the controller as lost and reconnects with new clients), never the
lock, so the stop service and the jog watchdog are never stuck behind it.
"""
from __future__ import annotations

import queue
import threading
from typing import Any, Callable, Optional, Protocol, Sequence, TypeVar

T = TypeVar("T")

CONTROLLER_NOT_RUNNING = 100
ROBOT_MODES = {-1: "NO_CONTROLLER", 0: "DISCONNECTED", 1: "CONFIRM_SAFETY", 2: "BOOTING", 3: "POWER_OFF",
               4: "POWER_ON", 5: "IDLE", 6: "BACKDRIVE", 7: "RUNNING", 8: "UPDATING_FIRMWARE",
               # Not a UR mode: a ros_control arm whose trajectory controller does not answer (ros_control backend).
               CONTROLLER_NOT_RUNNING: "CONTROLLER_NOT_RUNNING"}
SAFETY_MODES = {1: "NORMAL", 2: "REDUCED", 3: "PROTECTIVE_STOP", 4: "RECOVERY", 5: "SAFEGUARD_STOP",
                6: "SYSTEM_EMERGENCY_STOP", 7: "ROBOT_EMERGENCY_STOP", 8: "VIOLATION", 9: "FAULT",
                10: "VALIDATE_JOINT_ID", 11: "UNDEFINED_SAFETY_MODE", 12: "AUTOMATIC_MODE_SAFEGUARD_STOP",
                13: "SYSTEM_THREE_POSITION_ENABLING_STOP"}
RUNTIME_PLAYING = 2   # RTDE runtime_state: a program runs


def robot_mode_name(mode: int) -> str:
    return ROBOT_MODES.get(int(mode), f"UNKNOWN_{int(mode)}")


def safety_mode_name(mode: int) -> str:
    return SAFETY_MODES.get(int(mode), f"UNKNOWN_{int(mode)}")


class ControlInterface(Protocol):
    """The part of rtde_control.RTDEControlInterface the driver uses (same names and arguments)."""

    def isConnected(self) -> bool: ...
    def isProgramRunning(self) -> bool: ...
    def reuploadScript(self) -> bool: ...
    def stopScript(self) -> None: ...
    def disconnect(self) -> None: ...
    def moveJ(self, q: list[float], speed: float, acceleration: float, asynchronous: bool) -> bool: ...
    def moveL(self, pose: list[float], speed: float, acceleration: float, asynchronous: bool) -> bool: ...
    def speedJ(self, qd: list[float], acceleration: float, time: float) -> bool: ...
    def speedL(self, xd: list[float], acceleration: float, time: float) -> bool: ...
    def speedStop(self, a: float) -> bool: ...
    def stopJ(self, a: float, asynchronous: bool) -> None: ...
    def stopL(self, a: float, asynchronous: bool) -> None: ...
    def getAsyncOperationProgress(self) -> int: ...
    def getInverseKinematicsHasSolution(self, x: list[float], qnear: list[float], max_position_error: float,
                                        max_orientation_error: float) -> bool: ...
    def getInverseKinematics(self, x: list[float], qnear: list[float], max_position_error: float,
                             max_orientation_error: float) -> list[float]: ...
    def isJointsWithinSafetyLimits(self, q: list[float]) -> bool: ...
    def getForwardKinematics(self, q: list[float], tcp_offset: list[float]) -> list[float]: ...
    def getTCPOffset(self) -> list[float]: ...
    # Optional (the ros_control backend has it, ur_rtde does not): why the last move ended early, "" if it did not
    # (an aborted or rejected trajectory goal, with the controller's error code and text).
    # def getMoveError(self) -> str: ...
    # Optional (the ros_control backend has them): a move's target as the backend's own moves compute it, used
    # instead of getInverseKinematics / isJointsWithinSafetyLimits (driver.ManualDriver.move_target):
    # def getLinearMoveTarget(self, pose: list[float], qnear: list[float]) -> list[float]: ...  (where moveL ends)
    # def getJointLimitError(self, q: list[float]) -> str: ...  (why moveJ would refuse q, "" when it would not)


# What one poll reads (driver.read_snapshot), in this order; a client with readState() answers them in one call.
STATE_GETTERS = ("isConnected", "getTimestamp", "getActualQ", "getActualQd", "getActualTCPPose",
                 "getActualTCPSpeed", "getRobotMode", "getSafetyMode", "getSpeedScaling", "getRuntimeState",
                 "getActualDigitalInputBits", "getActualDigitalOutputBits")


class ReceiveInterface(Protocol):
    """The part of rtde_receive.RTDEReceiveInterface the driver uses."""

    def isConnected(self) -> bool: ...
    def disconnect(self) -> None: ...
    def getTimestamp(self) -> float: ...
    def getActualQ(self) -> list[float]: ...
    def getActualQd(self) -> list[float]: ...
    def getActualTCPPose(self) -> list[float]: ...
    def getActualTCPSpeed(self) -> list[float]: ...
    def getRobotMode(self) -> int: ...
    def getSafetyMode(self) -> int: ...
    def getSpeedScaling(self) -> float: ...
    def getRuntimeState(self) -> int: ...
    def getActualDigitalInputBits(self) -> int: ...
    def getActualDigitalOutputBits(self) -> int: ...


class IOInterface(Protocol):
    """The part of rtde_io.RTDEIOInterface the driver uses."""

    def setStandardDigitalOut(self, output_id: int, signal_level: bool) -> bool: ...
    def disconnect(self) -> None: ...


class DashboardInterface(Protocol):
    """The part of dashboard_client.DashboardClient the driver uses: stopping a program it did not start."""

    def connect(self, timeout_ms: int = ...) -> None: ...
    def stop(self) -> None: ...
    def disconnect(self) -> None: ...


class Connector(Protocol):
    """Makes the clients for a host; each raises (RuntimeError) when the controller cannot be reached.

    Optional attribute `control_takes_over` (default True): making the control client starts a program on the
    controller that ends any other program running there (ur_rtde uploads its control script). Calls that only
    read (the move preview) then never make it while another program runs."""

    def receive(self, host: str) -> ReceiveInterface: ...
    def io(self, host: str) -> IOInterface: ...
    def control(self, host: str) -> ControlInterface: ...
    def dashboard(self, host: str) -> DashboardInterface: ...


class CallTimeout(RuntimeError):
    """A controller call did not come back in time (the worker running it was abandoned)."""


class _Job:
    __slots__ = ("fn", "done", "result", "error")

    def __init__(self, fn: Callable[[], Any]) -> None:
        self.fn = fn
        self.done = threading.Event()
        self.result: Any = None
        self.error: Optional[BaseException] = None


class _Worker:
    def __init__(self, name: str) -> None:
        self.jobs: "queue.SimpleQueue[Optional[_Job]]" = queue.SimpleQueue()
        self.thread = threading.Thread(target=self._run, name=name, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while True:
            job = self.jobs.get()
            if job is None:
                return
            try:
                job.result = job.fn()
            except BaseException as e:  # handed to the caller
                job.error = e
            job.done.set()


def run_with_timeout(fn: Callable[[], T], timeout: float, name: str = "ur-call") -> T:
    """Run fn on a throwaway daemon thread; CallTimeout if it does not return in time (it is left behind)."""
    job = _Job(fn)
    w = _Worker(name)
    w.jobs.put(job)
    w.jobs.put(None)
    if not job.done.wait(timeout):
        raise CallTimeout(f"no answer within {timeout:g} s")
    if job.error is not None:
        raise job.error
    return job.result


class Gate:
    """One lock for every ur_rtde call; each call runs on the gate's worker thread, bounded by a timeout."""

    def __init__(self, timeout: float = 1.0) -> None:
        self.timeout = timeout
        self._lock = threading.Lock()
        self._worker = _Worker("ur-gate")

    def call(self, fn: Callable[[], T], timeout: Optional[float] = None) -> T:
        with self._lock:
            job = _Job(fn)
            self._worker.jobs.put(job)
            if not job.done.wait(timeout if timeout is not None else self.timeout):
                # The worker is stuck inside the call: leave it (and its client) behind, start a fresh one.
                self._worker.jobs.put(None)
                self._worker = _Worker("ur-gate")
                raise CallTimeout(f"the robot controller did not answer within {timeout or self.timeout:g} s")
            if job.error is not None:
                raise job.error
            return job.result

    def close(self) -> None:
        self._worker.jobs.put(None)


def keep_forever(client: object) -> None:
    """Never destroy this client object. Why: ur_rtde's destructors disconnect, and after the controller went away
    that write fails ("write: Broken pipe") inside a noexcept destructor, which aborts the whole process (seen when
    the sim restarted under a running driver). A dropped client is therefore disconnected explicitly (errors
    arrive as Python exceptions there) and then leaked: a few kB per lost connection."""
    import ctypes
    ctypes.pythonapi.Py_IncRef(ctypes.py_object(client))


class ClientGone(RuntimeError):
    """A call on a controller client the driver has dropped, or that another thread is still inside."""


class Guarded:
    """A controller client used by one thread at a time and never after it is dropped.

    Why: a client is not made to be closed on one thread while another is inside one of its calls. The gate
    serialises calls, but a call it gave up on (CallTimeout) still runs on its abandoned worker when the driver drops
    the lost connection's clients. So each client has its own lock: a call that finds it taken fails at once (the
    client is being dropped, or a call that never came back is inside it), and drop() ends or waits for the call
    inside before it disconnects. Methods are looked up on the client, so hasattr/getattr see its own."""

    def __init__(self, client: Any) -> None:
        self._client = client
        self._lock = threading.Lock()
        self._dropped = False

    def __getattr__(self, name: str) -> Any:
        attr = getattr(self._client, name)
        if not callable(attr):
            return attr

        def call(*args: Any, **kwargs: Any) -> Any:
            if not self._lock.acquire(blocking=False):
                raise ClientGone(f"{name}: the client is in use by a call that did not come back, or being closed")
            try:
                if self._dropped:
                    raise ClientGone(f"{name}: the client was dropped")
                return attr(*args, **kwargs)
            finally:
                self._lock.release()
        return call

    def drop(self, stop_script: bool = False) -> None:
        """Disconnect, once no call is inside the client; later calls raise ClientGone. A client that can end a call
        inside it at once (kill: the child process of ur_process) does so instead of waiting for it."""
        if not self._lock.acquire(blocking=False):
            kill = getattr(self._client, "kill", None)
            if kill is not None:
                kill()
            self._lock.acquire()
        try:
            if self._dropped:
                return
            self._dropped = True
            c = self._client
            if stop_script and hasattr(c, "stopScript") and c.isConnected():
                c.stopScript()
            c.disconnect()
        finally:
            self._lock.release()


def fk_lever(fk: Callable[[Sequence[float]], Sequence[float]], q: Sequence[float], joint: int,
             delta: float = 0.01) -> float:
    """Metres of TCP travel per radian of one joint (its distance from the joint axis), from two FK poses."""
    import math
    q2 = list(q)
    q2[joint] += delta
    a, b = fk(list(q)), fk(q2)
    chord = math.dist(a[:3], b[:3])
    return chord / (2 * math.sin(delta / 2))
