"""Where the suite's processes spend their CPU: every process it starts, by kind.

    python benchmarks/suite_processes.py -- make test      # any command; Linux only

``suite_cpu.py`` counts the CPU of a test's child processes when the test reaps them,
so a session's servers land on whichever test ends them, and processes nobody waits
for (Chromium's, PostgreSQL's backends) are not counted at all. This script runs the
command and reads ``/proc`` every ``--every`` seconds: each process started after the
command began, its command line and the CPU it had used when last seen. It then adds
them up by kind: the test workers, each ``calstation`` subcommand, the processes a
server spawns (its report processes and uvicorn's workers), Chromium, PostgreSQL. A
process's CPU after the last look before it ended is missed, so each figure is a floor
(at 20 looks a second, a short ``calstation --help`` loses at most 50 ms of its CPU).
"""

import argparse
import os
import re
import subprocess
import sys
import time
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path

PROC = Path("/proc")
#: Programs that exec what they start (``unshare … sh -c '…; exec "$@"'``, ``env -u X
#: python``): such a process's command line is read again until it is the program's.
EXECS = frozenset({"env", "sh", "bash", "unshare"})
TICKS_PER_S = os.sysconf("SC_CLK_TCK")


@dataclass
class Seen:
    """A process as last seen: its parent, command line and CPU seconds."""

    parent: int
    command: str
    cpu_s: float


def _stat(pid: str) -> tuple[int, float, int] | None:
    """Parent, CPU seconds (user + system) and start (clock ticks after boot) of ``pid``."""
    try:
        text = (PROC / pid / "stat").read_text()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2 :].split()
    return int(fields[1]), (int(fields[11]) + int(fields[12])) / TICKS_PER_S, int(fields[19])


def _command(pid: str) -> str:
    try:
        return (PROC / pid / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""


def _boot_ticks_now() -> int:
    """Clock ticks since boot, as a process's start time counts them."""
    return int(float((PROC / "uptime").read_text().split()[0]) * TICKS_PER_S)


def watch(command: list[str], every_s: float) -> tuple[int, dict[tuple[str, int], Seen]]:
    """Run ``command``; every process started meanwhile as last seen, by (pid, start)."""
    since = _boot_ticks_now() - 1
    seen: dict[tuple[str, int], Seen] = {}
    me = str(os.getpid())
    with subprocess.Popen(command) as run:
        while run.poll() is None:
            for entry in os.scandir(PROC):
                pid = entry.name
                if not pid.isdigit() or pid == me or (stat := _stat(pid)) is None:
                    continue
                parent, cpu_s, start = stat
                if start < since:
                    continue
                if (key := (pid, start)) not in seen:
                    seen[key] = Seen(parent, _command(pid), cpu_s)
                    continue
                process = seen[key]
                process.cpu_s = cpu_s
                if Path(process.command.split(" ", 1)[0]).name in EXECS:
                    process.command = _command(pid) or process.command
            time.sleep(every_s)
    return run.returncode, seen


def kind(process: Seen, by_pid: dict[int, Seen]) -> str:
    """What a process is, from its command line (and its parent's, for a spawned one)."""
    line = process.command
    if "multiprocessing" in line:
        if "resource_tracker" in line:
            return "multiprocessing resource tracker"
        spawner = by_pid.get(process.parent)
        return f"spawned by {kind(spawner, by_pid)}" if spawner else "spawned"
    program = line.split(" ", 1)[0]
    for name in ("chromium", "postgres", "docker-compose"):
        if name in program:  # not in the arguments: Chromium's profile lies in pytest's tmp
            return name
    if match := re.search(r"-m station(?:\s+(\S+))?", line):
        return f"calstation {match.group(1) or ''}".strip()
    if "exec(eval(sys.stdin" in line or "-m pytest" in line:
        return "pytest (main and workers)"
    if match := re.search(r"-m (\S+)|\s(\S+\.py)\b", line):
        return f"python {match.group(1) or match.group(2)}"
    return program or "(ended before its command line was read)"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--every", type=float, default=0.05, help="seconds between looks")
    parser.add_argument("command", nargs=argparse.REMAINDER, help="-- and the command to run")
    args = parser.parse_args()
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("no command: give it after --")
    returncode, seen = watch(command, args.every)
    by_pid = {int(pid): process for (pid, _), process in seen.items()}
    totals: dict[str, list[float]] = defaultdict(lambda: [0, 0.0])
    for process in seen.values():
        row = totals[kind(process, by_pid)]
        row[0] += 1
        row[1] += process.cpu_s
    print(f"\n{sum(cpu for _, cpu in totals.values()):.0f} s of CPU in processes started")
    print("| kind | processes | CPU | per process |\n|---|---|---|---|")
    for name, (count, cpu) in sorted(totals.items(), key=lambda item: -item[1][1]):
        if cpu >= 0.1:
            print(f"| {name} | {count:.0f} | {cpu:.1f} s | {cpu / count:.2f} s |")
    sys.exit(returncode)


if __name__ == "__main__":
    main()
