#!/usr/bin/python3
"""The display program of sim.ini: runs each G-code program named in
$LCNC_PROGRAMS (':'-separated, absolute paths) from X0 Y0 Z0 and writes
"<seconds> <path>" per program to $LCNC_OUT, the seconds being the time
motion was not in position (the HAL integrator `busy`). LinuxCNC shuts down
when this program exits."""
import os
import subprocess
import sys
import time

import linuxcnc


def busy():
    out = subprocess.run(["halcmd", "getp", "busy.out"], capture_output=True, text=True, check=True)
    return float(out.stdout.strip())


def wait_idle(s, c, timeout):
    """Until the interpreter is idle and motion in position with nothing
    queued for half a second on end (under G61 motion is in position for a
    moment at every block end)."""
    end = time.time() + timeout
    c.wait_complete(timeout)
    still = None
    while time.time() < end:
        s.poll()
        if s.interp_state == linuxcnc.INTERP_IDLE and s.inpos and s.queue == 0:
            still = still or time.time()
            if time.time() - still >= 0.5:
                return True
        else:
            still = None
        time.sleep(0.01)
    return False


def main():
    s, c = linuxcnc.stat(), linuxcnc.command()
    c.state(linuxcnc.STATE_ESTOP_RESET)
    c.state(linuxcnc.STATE_ON)
    c.wait_complete()
    progs = [p for p in os.environ.get("LCNC_PROGRAMS", "").split(":") if p]
    timeout = float(os.environ.get("LCNC_TIMEOUT", "900"))
    with open(os.environ["LCNC_OUT"], "w") as out:
        for p in progs:
            c.mode(linuxcnc.MODE_MDI)
            c.wait_complete()
            c.mdi("G90 G21 G0 X0 Y0 Z0")
            wait_idle(s, c, 60)
            time.sleep(0.2)
            t0 = busy()
            c.mode(linuxcnc.MODE_AUTO)
            c.wait_complete()
            c.program_open(p)
            c.auto(linuxcnc.AUTO_RUN, 0)
            time.sleep(0.2)
            ok = wait_idle(s, c, timeout)
            time.sleep(0.2)
            t = busy() - t0
            out.write(f"{t:.4f} {p}\n" if ok else f"timeout {p}\n")
            out.flush()
            s.poll()
            if s.task_state != linuxcnc.STATE_ON:
                out.write(f"error {p}\n")
                break
    c.state(linuxcnc.STATE_OFF)
    return 0


if __name__ == "__main__":
    sys.exit(main())
