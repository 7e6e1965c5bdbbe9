#!/usr/bin/env python3
"""Fault matrix (issue 19): injects faults into the RUNNING pipeline and measures the effect.

Run by scripts/fault_matrix.sh with Debian's /usr/bin/python3 (rospy) against launch/demo.launch
at the camera rate. For each fault, in turn: a baseline of --baseline seconds, the fault, then
up to --max-recovery seconds for the pipeline to come back. Measured per fault:
  - recovery (s): from the end of the fault (or its start, for faults that the pipeline should
    ride through) to the first set of the first 1 s window that shows pSfS reconstructing (sets
    learned into the background do not count) at >= 80 % of its baseline rate AND the tracker
    with the active targets it had before (for the room server: from its restart until the
    bridge has rejoined);
  - sets lost: frame sets the cameras produced in that span (baseline rate x span) that pSfS
    did not reconstruct;
  - message: the first WARN/ERROR on /rosout from a pipeline node during the fault, naming the
    cause (the rig's own "injecting fault" line excluded);
  - crash: the nodelet manager gone, or a process of the launch that died abnormally.
Each fault also carries its own assertions: the cause it must report (a WARN/ERROR on /rosout
containing a given text, at any time during the fault) and, for the faults the pipeline should
carry on through, at most --max-lost sets lost (degraded output instead of none).
Writes fault_matrix.md (a table), fault_matrix.csv and, with --junit, a JUnit file with one test
case per fault; exits 1 if any fault crashed something, did not recover within --max-recovery
or failed its assertions.
"""
import argparse
import os
import subprocess
import sys
import threading
import time
from xml.sax.saxutils import escape, quoteattr

import rospy
from rosgraph_msgs.msg import Log
from std_msgs.msg import Header, String
from nodelet.srv import NodeletLoad, NodeletUnload
from std_srvs.srv import Trigger

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from proc_tree import pid_of  # noqa: E402

try:
    from tabletop_msgs.msg import TrackedTargets
except ImportError:  # the devel space not sourced
    TrackedTargets = None


class Watch:
    """Counts pSfS's reconstructed sets, the tracker's active targets, and collects /rosout WARN+."""

    def __init__(self, ns):
        self.lock = threading.Lock()
        self.processed = []  # wall times of psfs/processed
        self.active = []     # (wall time, active targets)
        self.logs = []       # (wall time, node, level, text)
        self.joins = []      # wall times of the bridge's "joined room" lines
        rospy.Subscriber(ns + "/psfs/processed", Header, self.on_processed, queue_size=100)
        if TrackedTargets is not None:
            rospy.Subscriber(ns + "/hands/targets", TrackedTargets, self.on_targets, queue_size=100)
        rospy.Subscriber("/rosout_agg", Log, self.on_log, queue_size=1000)

    def on_processed(self, m):
        # Only sets made into volumes: a set learned into the background is no output.
        if m.frame_id != "reconstructed":
            return
        with self.lock:
            self.processed.append(time.monotonic())

    def on_targets(self, m):
        with self.lock:
            self.active.append((time.monotonic(), sum(1 for t in m.targets if t.active)))

    def on_log(self, m):
        if "cve_bridge: joined room" in m.msg:
            with self.lock:
                self.joins.append(time.monotonic())
        if m.level >= Log.WARN and "injecting fault" not in m.msg:
            with self.lock:
                self.logs.append((time.monotonic(), m.name, m.level, m.msg))

    def rate(self, t0, t1):
        with self.lock:
            return sum(1 for t in self.processed if t0 <= t < t1) / max(1e-6, t1 - t0)

    def count(self, t0, t1):
        with self.lock:
            return sum(1 for t in self.processed if t0 <= t < t1)

    def targets(self, t0, t1):
        """The most common active-target count in [t0, t1)."""
        with self.lock:
            vals = [a for t, a in self.active if t0 <= t < t1]
        return max(set(vals), key=vals.count) if vals else None

    def first_set_after(self, t0):
        with self.lock:
            after = [t for t in self.processed if t >= t0]
        return after[0] if after else None

    def any_log(self, t0, t1, text):
        with self.lock:
            return any(text in msg for t, _, _, msg in self.logs if t0 <= t < t1)

    def first_log(self, t0, t1):
        with self.lock:
            for t, name, level, text in self.logs:
                if t0 <= t < t1:
                    return f"{name}: {text}"
        return ""


def launch_log_since(path, offset):
    try:
        with open(path, "rb") as f:
            f.seek(offset)
            return f.read().decode(errors="replace")
    except OSError:
        return ""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pid", type=int, required=True, help="roslaunch's PID")
    ap.add_argument("--ns", default="/tabletop")
    ap.add_argument("--out", default="fault_matrix")
    ap.add_argument("--camera", type=int, default=3, help="the camera the per-camera faults hit")
    ap.add_argument("--duration", type=float, default=2.0, help="seconds of each timed fault")
    ap.add_argument("--baseline", type=float, default=6.0)
    ap.add_argument("--max-recovery", type=float, default=20.0)
    ap.add_argument("--room-port", type=int, default=0, help="the room server's port (restart fault)")
    ap.add_argument("--only", default="", help="comma-separated fault names to run")
    ap.add_argument("--log", default="", help="the launch's log file (crash lines)")
    ap.add_argument("--max-lost", type=int, default=3,
                    help="sets a fault that the pipeline should carry on through may cost at most")
    ap.add_argument("--junit", default="", help="write a JUnit file with one case per fault")
    a = ap.parse_args(rospy.myargv()[1:])
    os.makedirs(a.out, exist_ok=True)
    rospy.init_node("fault_matrix", anonymous=True, disable_signals=True)
    watch = Watch(a.ns)
    fault_pub = rospy.Publisher(a.ns + "/sim_rig/fault", String, queue_size=10, latch=False)
    c, d = a.camera, a.duration

    def rig(cmd):
        fault_pub.publish(String(data=cmd))

    # Wait for the pipeline: background learned, sets flowing, hands tracked.
    t_start = time.monotonic()
    while time.monotonic() - t_start < 180:
        now = time.monotonic()
        if watch.rate(now - 3, now) > 1.0 and (watch.targets(now - 3, now) or 0) >= 1:
            break
        time.sleep(0.5)
    else:
        print("[fault_matrix] the pipeline never started tracking", flush=True)
        return 1
    while fault_pub.get_num_connections() == 0:
        time.sleep(0.1)

    room_proc = {"p": None}

    def restart_room_server():
        # Not a ROS node (it needs no ROS): stopped by signal, like a crash or a redeploy.
        pid = pid_of(a.pid, "room_server")
        if pid is None:
            # It never started or died (e.g. its port taken): the restart cannot be judged.
            room_proc["missing"] = True
            print("[fault_matrix] no room_server process under the launch", flush=True)
        else:
            os.kill(pid, 15)
        time.sleep(d)
        exe = os.path.join(os.environ.get("TABLETOP_ROOT", "."), "devel/lib/cvephands_bridge/room_server")
        room_proc["p"] = subprocess.Popen([exe, "--port", str(a.room_port), "--static", "", "--status", "0"],
                                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    def reload_nodelet(name, kind):
        unload = rospy.ServiceProxy(a.ns + "/manager/unload_nodelet", NodeletUnload)
        load = rospy.ServiceProxy(a.ns + "/manager/load_nodelet", NodeletLoad)
        unload(name=a.ns + "/" + name)
        time.sleep(d)
        load(name=a.ns + "/" + name, type=kind, remap_source_args=[], remap_target_args=[],
             my_argv=[], bond_id="")

    def relearn_background():
        # The person is in view (the simulated rig's script keeps them there after its first
        # empty sets): what happens when the background is learned now.
        rospy.ServiceProxy(a.ns + "/psfs/relearn_background", Trigger)()

    # A fault: its name, the expected behaviour, how to make it, when it ends and what recovery
    # means. ends: "timed" (d after the injection), "returns" (when its action returns) or "ride"
    # (never: the pipeline should ride it through; judged from the injection). recovered:
    # "pipeline" (pSfS rate and tracked targets back) or "rejoin" (the bridge back in the room).
    # undo: what puts the rig back afterwards. reports: a text some WARN/ERROR during the fault
    # must contain (the cause named). carries_on: the pipeline should go on through the fault
    # with degraded output, so at most --max-lost sets may be lost.
    class Fault:
        def __init__(self, name, expected, action, ends, recovered="pipeline", undo=None,
                     reports="", carries_on=False):
            self.name, self.expected, self.action = name, expected, action
            self.ends, self.recovered, self.undo = ends, recovered, undo
            self.reports, self.carries_on = reports, carries_on

    faults = [
        Fault("camera_stops", f"camera {c} silent for {d:g} s: sets go on without it (degraded "
                              "sets, its slot empty), then with it again",
              lambda: rig(f"stop {c} {d}"), "timed", reports=f"published without cam{c}",
              carries_on=True),
        Fault("encoding_switch", f"camera {c} sends bgr8 for {d:g} s: a supported encoding, converted "
                                 "to rgb8, nothing lost",
              lambda: rig(f"encoding {c} bgr8 {d}"), "timed", carries_on=True),
        Fault("size_switch", f"camera {c} sends 160x120 for {d:g} s: refused as a size mismatch, "
                             "the sets go on without it",
              lambda: rig(f"size {c} 160 120 {d}"), "timed", reports="does not match camera_info",
              carries_on=True),
        Fault("camera_info_nan", f"camera {c}'s camera_info has NaN intrinsics for {d:g} s: that "
                                 "camera is left out or its info ignored",
              lambda: rig(f"nan_info {c} {d}"), "timed", reports="invalid camera_info",
              carries_on=True),
        Fault("tf_missing", f"camera {c}'s images name an optical frame without tf for {d:g} s: "
                            "reported, the sets go on without it",
              lambda: rig(f"frame {c} cam{c}_unknown_optical_frame {d}"), "timed",
              reports=f"cam{c}: no tf", carries_on=True),
        Fault("tf_change", f"camera {c}'s tf re-broadcast 3 cm off for {d:g} s (the camera did not "
                           "move): the new pose is adopted within 1 s and reported, the volumes "
                           "degrade, nothing stops; the true tf again after",
              lambda: rig(f"tf {c} 0.03 0 0 {d}"), "timed", reports=f"cam{c}: its tf changed",
              carries_on=True),
        Fault("clock_back", "every stamp 30 s earlier from now on (a bag played in a loop): the "
                            "synchroniser starts over, the stages follow without waiting",
              lambda: rig("clock -30 0"), "ride", undo=lambda: rig("clear"),
              reports="time went back"),
        Fault("person_at_learning", "the background relearned (relearn_background) while the person "
                                    "is in view: each learning set is refused and reported (the "
                                    "model used before sees a body), and after learning_frames of "
                                    "them that model is taken back",
              relearn_background, "returns", reports="learned before again"),
        Fault("light_on", "every camera 40 % brighter from now on: the classifier's gain compensation "
                          "rides it through",
              lambda: rig("brightness 1.4 0"), "ride", undo=lambda: rig("clear"), carries_on=True),
        Fault("room_server_restart", f"the room server killed and restarted {d:g} s later: the bridge "
                                     "rejoins (back-off), the pipeline never waits; recovery = rejoin "
                                     "after the restart",
              restart_room_server, "returns", recovered="rejoin",
              reports=("cannot join room", "lost room")),
        Fault("nodelet_reload", f"the MPF tracker nodelet unloaded and loaded again {d:g} s later: "
                                "pSfS goes on, tracking starts over",
              lambda: reload_nodelet("mpf", "hand_tracking/Mpf"), "returns"),
    ]
    only = {x for x in a.only.split(",") if x}
    rows, ok = [], True
    for fault in faults:
        name = fault.name
        if only and name not in only:
            continue
        manager = pid_of(a.pid, "manager")
        log_offset = os.path.getsize(a.log) if a.log and os.path.exists(a.log) else 0
        t0 = time.monotonic()
        time.sleep(a.baseline)
        b0, b1 = t0, time.monotonic()
        base_rate = watch.rate(b0, b1)
        base_targets = watch.targets(b0, b1) or 0
        f0 = time.monotonic()
        print(f"[fault_matrix] {name}: baseline {base_rate:.1f} sets/s, {base_targets} targets; injecting",
              flush=True)
        fault.action()
        if fault.ends == "timed":
            time.sleep(max(0.0, f0 + d - time.monotonic()))
        ref = f0 if fault.ends == "ride" else time.monotonic()  # recovery is counted from here
        recovered = None
        while time.monotonic() - ref < a.max_recovery:
            time.sleep(0.25)
            now = time.monotonic()
            if fault.recovered == "rejoin":
                with watch.lock:
                    back = [t for t in watch.joins if t > f0]
                if back:
                    recovered = max(0.0, back[0] - ref)
                    break
                continue
            if now - ref < 1.0:
                continue
            if watch.rate(now - 1.0, now) >= 0.8 * base_rate and (watch.targets(now - 1.0, now) or 0) >= base_targets:
                # The first set of the window that shows the pipeline back (not the first after the
                # fault: on a slow machine sets made before it are still being finished then).
                first = watch.first_set_after(max(ref, now - 1.0))
                recovered = max(0.0, (first if first is not None else now) - ref)
                break
        end = time.monotonic()
        lost = max(0, int(round(base_rate * (end - f0))) - watch.count(f0, end))
        message = watch.first_log(f0, end)
        problems = []
        if fault.name == "room_server_restart" and room_proc.get("missing"):
            problems.append(f"no room_server was running before the fault (it did not start or "
                            f"died: port {a.room_port} taken? see launch.log)")
        if recovered is None:
            problems.append(f"no recovery within {a.max_recovery:g} s")
        texts = fault.reports if isinstance(fault.reports, tuple) else (fault.reports,)
        if fault.reports and not any(watch.any_log(f0, end, t) for t in texts):
            problems.append("no WARN/ERROR containing " + " or ".join(f"'{t}'" for t in texts))
        if fault.carries_on and lost > a.max_lost:
            problems.append(f"{lost} sets lost (at most {a.max_lost})")
        if fault.undo:
            fault.undo()
        time.sleep(1.0)
        # A crash: the nodelet manager gone, or a process that died abnormally. (The reload's
        # loader process ends with its nodelet's bond: expected. The room server is stopped on
        # purpose.)
        text = launch_log_since(a.log, log_offset) if a.log else ""
        died = [l for l in text.splitlines()
                if ("process has died" in l and "room_server" not in l and "/mpf-" not in l)
                or "Segmentation fault" in l or "terminate called" in l]
        crash = (manager is not None and not os.path.exists(f"/proc/{manager}")) or bool(died)
        if crash:
            problems.insert(0, "crash: " + ("; ".join(died[:2]) or "the nodelet manager is gone"))
        if problems:
            ok = False
        rows.append((name, fault.expected, recovered, lost, message, crash, problems))
        print(f"[fault_matrix] {name}: recovered {'no' if recovered is None else f'{recovered:.1f} s'}, "
              f"{lost} sets lost, crash {'YES' if crash else 'no'}; message: {message or '(none)'}"
              f"{'; FAILED: ' + '; '.join(problems) if problems else ''}", flush=True)
    if room_proc["p"] is not None:
        room_proc["p"].terminate()
    with open(os.path.join(a.out, "fault_matrix.csv"), "w") as f:
        f.write("fault,recovery_s,sets_lost,crash,message\n")
        for name, _, rec, lost, msg, crash, _ in rows:
            f.write(f"{name},{'' if rec is None else f'{rec:.2f}'},{lost},{int(crash)},\"{msg.replace(chr(34), chr(39))}\"\n")
    with open(os.path.join(a.out, "fault_matrix.md"), "w") as f:
        f.write("| fault | expected | recovery | sets lost | crash | first WARN/ERROR on /rosout |\n")
        f.write("|---|---|---:|---:|---|---|\n")
        for name, exp, rec, lost, msg, crash, _ in rows:
            f.write(f"| {name} | {exp} | {'not within ' + str(a.max_recovery) + ' s' if rec is None else f'{rec:.1f} s'} "
                    f"| {lost} | {'YES' if crash else 'no'} | {msg.replace('|', '/')[:200] or '(none)'} |\n")
    if a.junit:
        with open(a.junit, "w") as f:
            failures = sum(1 for r in rows if r[6])
            f.write('<?xml version="1.0" encoding="UTF-8"?>\n')
            f.write(f'<testsuite name="fault_matrix" tests="{len(rows)}" failures="{failures}" errors="0">\n')
            for name, exp, rec, lost, msg, crash, problems in rows:
                f.write(f'  <testcase classname="fault_matrix" name={quoteattr(name)}>')
                if problems:
                    detail = (f"expected: {exp}\nrecovery: {rec}\nsets lost: {lost}\n"
                              f"first WARN/ERROR: {msg}")
                    f.write(f'<failure message={quoteattr("; ".join(problems))}>{escape(detail)}</failure>')
                f.write("</testcase>\n")
            f.write("</testsuite>\n")
    print(f"[fault_matrix] {'PASS' if ok else 'FAIL'}: {os.path.join(a.out, 'fault_matrix.md')}", flush=True)
    rospy.signal_shutdown("done")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
