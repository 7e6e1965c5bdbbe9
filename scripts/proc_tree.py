"""The processes of a running launch, from /proc (Linux): shared by soak_monitor.py and
fault_matrix.py."""
import os


def processes_of(root):
    """PIDs of root and all its descendants (parents from /proc/<pid>/stat)."""
    parent = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                stat = f.read()
            parent[int(entry)] = int(stat[stat.rindex(")") + 2:].split()[1])
        except (OSError, ValueError):
            continue
    out, frontier = {root}, [root]
    while frontier:
        p = frontier.pop()
        for c, pp in parent.items():
            if pp == p and c not in out:
                out.add(c)
                frontier.append(c)
    return out


def command_line(pid):
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            return [a.decode(errors="replace") for a in f.read().split(b"\0") if a]
    except OSError:
        return []


def label_of(pid):
    """A process's ROS name (__name:=) or its program name (the script for python), or None."""
    args = command_line(pid)
    for a in args:
        if a.startswith("__name:="):
            return a[len("__name:="):]
    if not args:
        return None
    prog = os.path.basename(args[0])
    if prog.startswith("python") and len(args) > 1:
        prog = os.path.basename(args[1])
    return prog


def pid_of(root, label):
    """The PID under root whose label is `label`, or None."""
    for pid in processes_of(root):
        if label_of(pid) == label:
            return pid
    return None


def rss_mb(pid):
    """Resident memory (VmRSS) in MB, 0 if the process is gone."""
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return 0.0
