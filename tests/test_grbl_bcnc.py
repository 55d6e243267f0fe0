#!/usr/bin/python3
# bCNC (Debian's package) drives `motionctl serve`: its Sender with the GRBL1
# controller class, without a display, streams a job to the serve's
# pseudo-terminal and then to socket://127.0.0.1:PORT, with a feed hold, a
# resume and a feed override in the middle, and must end with every line
# acknowledged, no error and the machine at the job's end point.
#
# usage: /usr/bin/python3 test_grbl_bcnc.py MOTIONCTL [--dry-run|--sim]
# Debian's python3 on purpose: bCNC needs Debian's tk and pyserial.
# --sim: `motionctl --sim serve`, the board backend on the virtual board (its
# own, in a private runtime directory, stopped at the end), with a shorter
# job: the virtual board runs in real time. MPos is then the encoders'
# position, which a stop reports once the servo is within 2 counts (5 um)
# of its command.
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time

BCNC = "/usr/share/bcnc/bCNC"
if not os.path.isdir(BCNC):
    print("bCNC is not installed: run scripts/deps.sh (it installs Debian's bcnc)")
    sys.exit(1)
motionctl = sys.argv[1]
mode = sys.argv[2] if len(sys.argv) > 2 else "--dry-run"
if mode not in ("--dry-run", "--sim"):
    print("usage: test_grbl_bcnc.py MOTIONCTL [--dry-run|--sim]")
    sys.exit(2)
work = tempfile.mkdtemp(prefix="mc_bcnc_")
if mode == "--sim":
    os.environ["XDG_RUNTIME_DIR"] = work  # a virtual board of our own
# mm: the servo's in-position band (2 counts) on --sim; exact on --dry-run. The
# slack absorbs the float subtraction: 12.505 - 12.5 is 0.0050000000000008, and a
# position exactly 2 counts off is inside the band.
END_TOLERANCE = 0.005 + 1e-9
os.environ["HOME"] = work  # bCNC reads and writes ~/.bCNC
sys.path[:0] = [BCNC, BCNC + "/lib", BCNC + "/plugins", BCNC + "/controllers"]

import Utils  # noqa: E402

Utils.loadConfiguration()
from CNC import CNC, WAIT  # noqa: E402
from Sender import Sender  # noqa: E402

# Only a guard: every wait below ends on what bCNC parsed from the server.
GUARD_S = 120


class Headless(Sender):
    """The sender of bCNC's application, less its window. Every line bCNC's
    controller parses from the server wakes the waits below (they test what
    bCNC made of it), and status reports are counted."""

    def __init__(self):
        Sender.__init__(self)
        self.heard = threading.Condition()
        self.reports = 0

    def listen(self):
        parse = self.mcontrol.parseLine

        def parse_and_tell(line, cline, sline):
            result = parse(line, cline, sline)
            with self.heard:
                if line.startswith("<"):
                    self.reports += 1
                self.heard.notify_all()
            return result

        self.mcontrol.parseLine = parse_and_tell

    def wait_for(self, what, pred):
        with self.heard:
            if not self.heard.wait_for(pred, timeout=GUARD_S):
                raise AssertionError("timed out waiting for " + what + "; state " + str(CNC.vars["state"]))

    def disable(self):
        pass

    def enable(self):
        pass


def job():
    # On --sim, faster feeds and fewer zig-zags: the virtual board runs in real time.
    slow, zigzags = (600, 200) if mode == "--dry-run" else (2400, 20)
    lines = ["G21 G90 G94", "G0 X0 Y0 Z0", "G1 X20 F%d" % slow, "G2 X30 Y10 I0 J10", "G1 Y30",
             "G3 X20 Y40 I-10 J0"]
    for i in range(zigzags):
        lines.append("G1 X%.1f Y%s F3000" % (20 - 0.1 * (i + 1), "40" if i % 2 else "39.5"))
    lines += ["G1 X0 Y40 F%d" % (2 * slow), "G1 Y0", "G0 X12.5 Y7.5"]
    return lines


def run(device):
    s = Headless()
    s.listen()
    errors = []
    received = []
    heard = []  # everything bCNC logged, for the failure message
    s.open(device, 115200)

    def drain_log():
        while not s.log.empty():
            kind, text = s.log.get()
            heard.append(str(text))
            if kind == Sender.MSG_ERROR or re.match(r"(error|ALARM)", str(text)):
                errors.append(text)
            if kind == Sender.MSG_OK:
                received.append(text)
        return errors

    def wait_for(what, pred):
        try:
            s.wait_for(what, pred)
        except AssertionError as e:
            drain_log()
            raise AssertionError("%s; bCNC's last log lines: %s" % (e, heard[-8:])) from None

    wait_for("the first status report", lambda: CNC.vars["state"] == "Idle")
    lines = job()
    # bCNC.Application.run() with the lines given, less its window.
    s.initRun()
    s._runLines = sys.maxsize
    s._gcount = 0
    CNC.vars["running"] = True
    n = 1  # the closing WAIT
    for line in CNC.compile(lines):
        if line is not None:
            s.queue.put(line + "\n" if isinstance(line, str) else line)
            n += 1
    s._runLines = n
    s.queue.put((WAIT,))

    wait_for("the job to run", lambda: CNC.vars["state"] == "Run" and not drain_log())
    wait_for("20 lines acknowledged", lambda: len(drain_log()) == 0 and len(received) > 20)
    s.feedHold()
    wait_for("Hold:0", lambda: CNC.vars["state"] == "Hold:0")
    held = (CNC.vars["mx"], CNC.vars["my"])
    # "Nothing moves" is four more status reports at the held position.
    after = s.reports + 4
    wait_for("four status reports while held", lambda: s.reports >= after)
    now = (CNC.vars["mx"], CNC.vars["my"])
    assert CNC.vars["state"] == "Hold:0" and all(abs(a - b) <= END_TOLERANCE for a, b in zip(now, held)), \
        "moved while held: %s -> %s" % (held, now)
    print("%s: held at X%.3f Y%.3f" % (device, held[0], held[1]))
    s.resume()
    wait_for("Run after the resume", lambda: CNC.vars["state"] == "Run")
    CNC.vars["_OvFeed"] = 110
    CNC.vars["_OvChanged"] = True
    wait_for("Ov: 110", lambda: CNC.vars["OvFeed"] == 110)
    wait_for("the end of the job",
             lambda: not drain_log() and s._gcount >= s._runLines and CNC.vars["state"] == "Idle")
    end = (CNC.vars["mx"], CNC.vars["my"], CNC.vars["mz"])
    print("%s: %d/%d lines done, feed override %d %%, machine at %s" %
          (device, s._gcount, s._runLines, CNC.vars["OvFeed"], end))
    s.runEnded()
    s.close()
    assert not errors, "errors: %s" % errors
    assert all(abs(a - b) <= END_TOLERANCE for a, b in zip(end, (12.5, 7.5, 0.0))), \
        "ended at %s, not X12.5 Y7.5 Z0" % (end,)


def main():
    link = os.path.join(work, "motioncore")
    # --sim: the virtual board is paced to the wall clock and catches up after the
    # OS has descheduled it, which a loaded machine does for longer than the
    # board's 100 ms watchdog: give it a second.
    machine = ["serve", "--dry-run"] if mode == "--dry-run" else ["--sim", "serve", "--watchdog", "1s"]
    serve = subprocess.Popen([motionctl] + machine + ["--pty", link, "--tcp", "0", "--settings",
                                                      os.path.join(work, "grbl.toml")], stdout=subprocess.PIPE,
                             text=True)
    try:
        out = ""
        while "Ctrl-C stops." not in out:
            line = serve.stdout.readline()
            if not line:
                raise AssertionError("motionctl serve stopped: " + out)
            out += line
        port = int(re.search(r"tcp: +127\.0\.0\.1:(\d+)", out).group(1))
        t0 = time.monotonic()
        run(link)
        t1 = time.monotonic()
        run("socket://127.0.0.1:%d" % port)
        print("PASS: bCNC ran the job on %s on the PTY (%.1f s) and over TCP (%.1f s)" %
              (mode, t1 - t0, time.monotonic() - t1))
        return 0
    except AssertionError as e:
        print("FAIL: %s" % e)
        return 1
    finally:
        serve.terminate()
        serve.wait()
        if mode == "--sim":
            subprocess.run([motionctl, "sim", "stop"], stdout=subprocess.DEVNULL)
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    os._exit(code)  # bCNC's serial thread is not a daemon
