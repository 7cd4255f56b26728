"""Script ports 30001-30003: accept URScript uploads. The ur_rtde control script is recognised and run
natively by the register executor; a few one-line commands are honoured; anything else is logged and refused.
"""
from __future__ import annotations

import logging
import os
import re
import socket

from .controller import Controller
from .executor import ControlScriptProgram
from .tcp import TcpServer

log = logging.getLogger("sim.script")

_SET_DO = re.compile(r"^set_(?:standard_)?digital_out\(\s*(\d+)\s*,\s*(True|False|true|false|1|0)\s*\)$")


class ScriptServer(TcpServer):
    def __init__(self, host: str, port: int, controller: Controller) -> None:
        super().__init__(host, port, f"script-{port}")
        self.ctl = controller
        self.last_script = ""

    def handle(self, sock: socket.socket) -> None:
        buf = ""
        program: list[str] = []
        while not self.stopping():
            data = sock.recv(65536)
            if not data:
                return
            buf += data.decode("utf-8", "replace")
            while "\n" in buf:
                line, buf = buf.split("\n", 1)
                if program:
                    program.append(line)
                    if line.rstrip() == "end":  # a top-level 'end' closes the program definition
                        self.run_script("\n".join(program) + "\n")
                        program = []
                elif re.match(r"^(def|sec)\s+\w+\(\)\s*:", line):
                    program = [line]
                elif line.strip():
                    self.run_line(line.strip())

    def run_script(self, script: str) -> None:
        self.last_script = script
        dump = os.environ.get("SIM_DUMP_SCRIPT")
        if dump:  # debugging aid: keep the last uploaded program
            with open(dump, "w") as fh:
                fh.write(script)
        name = re.match(r"^(?:def|sec)\s+(\w+)", script)
        if "rtde_control" in script and "read_input_integer_register" in script:
            if not self.ctl.start_program(ControlScriptProgram(script)):
                log.error("control script not started: robot not ready (power on + brake release first)")
        else:
            log.warning("script %s: only the ur_rtde control script is supported, ignored",
                        name.group(1) if name else "?")

    def run_line(self, line: str) -> None:
        m = _SET_DO.match(line)
        if m:
            self.ctl.set_digital_out(int(m.group(1)), m.group(2).lower() in ("true", "1"))
        elif line.startswith(("stopj(", "stopl(")):
            with self.ctl.lock:
                self.ctl.stop_program("stopped by a script command")
        elif line.startswith("textmsg("):
            log.info("script message: %s", line)
        else:
            log.warning("script command not supported, ignored: %r", line[:80])
