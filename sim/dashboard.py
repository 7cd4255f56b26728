"""Dashboard server (port 29999): line commands with the replies a PolyScope 5 controller gives."""
from __future__ import annotations

import logging
import socket

from .controller import POLYSCOPE_VERSION, SERIAL_NUMBER, Controller, RobotMode, RuntimeState, SafetyMode
from .tcp import TcpServer

log = logging.getLogger("sim.dashboard")

WELCOME = "Connected: Universal Robots Dashboard Server"


class UrpProgram:
    """A program loaded from a .urp file: the simulator has no PolyScope interpreter, so it idles until stopped."""

    def __init__(self, name: str) -> None:
        self.name = name

    def tick(self, ctl: Controller) -> None:
        pass

    def on_stop(self, ctl: Controller) -> None:
        pass


def program_name(ctl: Controller) -> str:
    if ctl.program is not None and ctl.program.name != "rtde_control":
        return ctl.program.name
    return ctl.loaded_program.rsplit("/", 1)[-1] if ctl.loaded_program else "<unnamed>"


def reply(ctl: Controller, line: str) -> str:
    """The controller's answer to one dashboard command line."""
    cmd = line.strip()
    low = cmd.lower()
    if low == "power on":
        if ctl.safety_mode != SafetyMode.NORMAL:
            return "Failed to execute: power on"
        ctl.power_on()
        return "Powering on"
    if low == "power off":
        ctl.power_off()
        return "Powering off"
    if low == "brake release":
        ctl.brake_release()
        return "Brake releasing"
    if low == "play":
        if ctl.runtime_state == RuntimeState.PAUSED and ctl.resume_program():
            return "Starting program"
        if ctl.loaded_program and ctl.runtime_state == RuntimeState.STOPPED \
                and ctl.start_program(UrpProgram(ctl.loaded_program.rsplit("/", 1)[-1])):
            return "Starting program"
        return "Failed to execute: play"
    if low == "stop":
        # Answered 'Stopped' also when nothing runs: ur_rtde calls stop right after its own stop script.
        ctl.stop_program("stopped from the dashboard")
        return "Stopped"
    if low == "pause":
        return "Pausing program" if ctl.pause_program() else "Failed to execute: pause"
    if low == "running":
        return f"Program running: {'true' if ctl.runtime_state == RuntimeState.PLAYING else 'false'}"
    if low == "robotmode":
        return f"Robotmode: {RobotMode(ctl.robot_mode).name}"
    if low == "safetymode":
        return f"Safetymode: {SafetyMode(ctl.safety_mode).name}"
    if low == "safetystatus":
        return f"Safetystatus: {SafetyMode(ctl.safety_mode).name}"
    if low == "programstate":
        state = {RuntimeState.PLAYING: "PLAYING", RuntimeState.PAUSED: "PAUSED"}.get(ctl.runtime_state, "STOPPED")
        return f"{state} {program_name(ctl)}"
    if low == "unlock protective stop":
        if ctl.unlock_protective_stop():
            return "Protective stop releasing"
        return ("Cannot unlock protective stop until 5s after occurrence. "
                "Always inspect cause of protective stop before unlocking")
    if low == "close safety popup":
        return "closing safety popup"
    if low == "close popup":
        return "closing popup"
    if low.startswith("popup "):
        return "showing popup"
    if low == "polyscopeversion":
        return POLYSCOPE_VERSION
    if low == "version":
        return POLYSCOPE_VERSION.split(" ")[1]
    if low == "get serial number":
        return SERIAL_NUMBER
    if low == "get robot model":
        return "UR5"
    if low == "is in remote control":
        return "true"
    if low == "get operational mode":
        return "NONE"
    if low == "isprogramsaved":
        return f"true {program_name(ctl)}"
    if low == "get loaded program":
        return f"Loaded program: {ctl.loaded_program}" if ctl.loaded_program else "No program loaded"
    if low.startswith("load "):
        path = cmd[5:].strip()
        if not path.endswith(".urp"):
            return f"File not found: {path}"
        ctl.loaded_program = path if path.startswith("/") else f"/programs/{path}"
        return f"Loading program: {ctl.loaded_program}"
    if low.startswith("addtolog "):
        log.info("dashboard log: %s", cmd[9:])
        return "Added log message"
    if low == "restart safety":
        ctl.power_off()
        ctl.unlock_protective_stop(force=True)
        return "Restarting safety"
    if low == "shutdown":
        ctl.power_off()
        return "Shutting down"
    if low == "clear operational mode":
        return "No longer controlling the operational mode. Current operational mode: 'NONE'."
    log.warning("dashboard: unknown command %r", cmd)
    return f"could not understand: '{cmd}'"


class DashboardServer(TcpServer):
    port = 29999

    def __init__(self, host: str, controller: Controller) -> None:
        super().__init__(host, self.port, "dashboard")
        self.ctl = controller

    def handle(self, sock: socket.socket) -> None:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.sendall((WELCOME + "\n").encode())
        buf = b""
        while not self.stopping():
            data = sock.recv(4096)
            if not data:
                return
            buf += data
            if len(buf) > 65536 and b"\n" not in buf:  # a client that never ends its line
                log.warning("dashboard: line too long, closing connection")
                return
            while b"\n" in buf:
                raw, buf = buf.split(b"\n", 1)
                line = raw.decode("utf-8", "replace").strip("\r")
                if line.strip().lower() == "quit":
                    sock.sendall(b"Disconnected\n")
                    return
                sock.sendall((reply(self.ctl, line) + "\n").encode())
