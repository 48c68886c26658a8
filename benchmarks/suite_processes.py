"""Where the suite's processes spend their CPU: every process it starts, by kind.

    python benchmarks/suite_processes.py -- make test      # any command; Linux only

``suite_cpu.py`` counts the CPU of a test's child processes when the test reaps them,
so a session's servers land on whichever test ends them, and processes nobody waits
for (report processes that outlive their server, PostgreSQL's backends) are not counted
at all. This script runs the command and looks through ``/proc`` every ``--every``
seconds for the processes of the command's tree, and for the PostgreSQL backends started
meanwhile, which serve its connections: each one's command line (read again after an
exec) and the CPU it had used when last seen. It then adds them up by kind: the test
processes, each ``calstation`` subcommand, the processes a server spawns (its report
processes and uvicorn's workers), Chromium, PostgreSQL. A process's CPU after the last
look before it ended is missed (the pause between looks plus a look's own pass over
``/proc``), and so is a process whose parent ended before any look found it; each
figure is a floor.
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
TICKS_PER_S = os.sysconf("SC_CLK_TCK")
#: A process id and its start (clock ticks after boot): one process, whatever reuses the id.
Key = tuple[int, int]


@dataclass
class Seen:
    """A process as last seen: its parent, its name (``comm``: it changes at an exec),
    command line and CPU seconds."""

    parent: Key | None
    name: str
    command: str
    cpu_s: float


def _stat(pid: str) -> tuple[str, int, float, int] | None:
    """Name, parent, CPU seconds (user + system) and start of process ``pid``."""
    try:
        text = (PROC / pid / "stat").read_text()
    except OSError:
        return None
    name = text[text.index("(") + 1 : text.rindex(")")]
    fields = text[text.rindex(")") + 2 :].split()
    cpu_s = (int(fields[11]) + int(fields[12])) / TICKS_PER_S
    return name, int(fields[1]), cpu_s, int(fields[19])


def _command(pid: str) -> str:
    try:
        return (PROC / pid / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""


def watch(command: list[str], every_s: float) -> tuple[int, dict[Key, Seen]]:
    """Run ``command``; every process of its tree (and every PostgreSQL backend started
    meanwhile, which serve its connections) as last seen.

    A process belongs to the tree when its parent does at the first look that finds it
    (a process whose parent ended before that look, and was handed to init, is missed).
    """
    seen: dict[Key, Seen] = {}
    with subprocess.Popen(command) as run:
        root = _stat(str(run.pid))
        if root is None:  # it ended at once
            return run.wait(), seen
        seen[(run.pid, root[3])] = Seen(None, root[0], _command(str(run.pid)), root[2])
        since = root[3]
        while run.poll() is None:
            found = []
            for entry in os.scandir(PROC):
                if entry.name.isdigit() and (stat := _stat(entry.name)) is not None:
                    found.append((int(entry.name), *stat))
            current = {pid: (pid, start) for pid, _, _, _, start in found}
            for pid, name, parent, cpu_s, start in found:
                key = (pid, start)
                if (process := seen.get(key)) is not None:
                    process.cpu_s = cpu_s
                    if name != process.name:  # it exec'd: read what it runs now
                        process.name, process.command = name, _command(str(pid))
                    continue
                parent_key = current.get(parent)
                if start >= since and (parent_key in seen or name.startswith("postgres")):
                    seen[key] = Seen(parent_key, name, _command(str(pid)), cpu_s)
            time.sleep(every_s)
    return run.returncode, seen


def kind(process: Seen, seen: dict[Key, Seen]) -> str:
    """What a process is, from its command line (and its parent's, for a spawned one)."""
    line = process.command
    if "from multiprocessing" in line:
        if "resource_tracker" in line:
            return "multiprocessing resource tracker"
        spawner = seen.get(process.parent) if process.parent else None
        return f"spawned by {kind(spawner, seen)}" if spawner else "spawned"
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
    return program or f"({process.name})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--every", type=float, default=0.05, help="seconds between looks")
    parser.add_argument("command", nargs=argparse.REMAINDER, help="-- and the command to run")
    args = parser.parse_args()
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("no command: give it after --")
    returncode, seen = watch(command, args.every)
    totals: dict[str, list[float]] = defaultdict(lambda: [0, 0.0])
    for process in seen.values():
        row = totals[kind(process, seen)]
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
