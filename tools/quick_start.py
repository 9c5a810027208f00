"""Run the README's quick start as written and record what it printed and how long it took.

The commands are read from the README between the `quick-start` markers (the block the
docs' quick-start page includes), so what runs is exactly what a newcomer types:

- ``source .venv/bin/activate`` is done by putting this interpreter's ``bin/`` first on PATH;
- ``tvist twin-server ...`` (step 1, "a second terminal") starts in the background; the
  other commands run once it prints ``twin server ready``, and it is stopped with Ctrl-C
  (SIGINT) at the end;
- every other command runs in order in a fresh working folder and must exit 0.

``python tools/quick_start.py`` (``make quick-start``) writes ``out/quick-start/run.json``:
per command its wall time in seconds, exit code and the lines it printed, plus the time
from the server being ready to the end of the first shaped run. The docs' quick-start page
shows that record (docs/gen_pages.py). It uses UR's fixed ports on 127.0.0.1, so nothing
else may serve them meanwhile; it is not part of ``make test``
(tests/integration/test_campaign_road_twin.py runs the same road on free ports).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
START, END = "[start:quick-start]", "[end:quick-start]"
SERVER = "tvist twin-server"
READY = "twin server ready"
#: How long the server may take to print READY (s): MuJoCo model build on a loaded machine.
READY_TIMEOUT_S = 300.0


def quick_start_commands(readme: str) -> list[str]:
    """The shell commands of the README's quick-start block, continuation lines joined,
    comments and blank lines dropped, in order."""
    if START not in readme or END not in readme:
        raise ValueError(f"README has no block between {START} and {END}")
    block = readme.split(START, 1)[1].split(END, 1)[0]
    lines = block.split("```sh", 1)[1].split("```", 1)[0].splitlines()
    commands: list[str] = []
    pending = ""
    for line in lines:
        stripped = line.strip()
        if not pending and (not stripped or stripped.startswith("#")):
            continue
        if stripped.endswith("\\"):
            pending += stripped[:-1]
            continue
        commands.append(pending + stripped)
        pending = ""
    if pending:
        raise ValueError(f"quick start ends inside a continued line: {pending!r}")
    return commands


def _first_shaped_run(commands: list[str]) -> int:
    """Index of the first ``tvist run`` that shapes (not ``--unshaped``)."""
    for i, command in enumerate(commands):
        if command.startswith("tvist run ") and "--unshaped" not in command:
            return i
    raise ValueError("the quick start has no shaped 'tvist run'")


def _git_commit() -> str | None:
    out = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
    )
    return out.stdout.strip() or None


def _start_server(command: str, env: dict[str, str], cwd: Path) -> subprocess.Popen[str]:
    server = subprocess.Popen(
        command,
        shell=True,
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    deadline = time.monotonic() + READY_TIMEOUT_S
    assert server.stdout is not None
    for line in server.stdout:
        print(f"  [server] {line.rstrip()}", flush=True)
        if READY in line:
            return server
        if time.monotonic() > deadline:
            break
    _stop(server)
    raise RuntimeError(f"{command!r} did not print {READY!r} within {READY_TIMEOUT_S:.0f} s")


def _stop(server: subprocess.Popen[str]) -> None:
    """Ctrl-C, as the README says; kill if it does not stop within 20 s."""
    if server.poll() is None:
        os.killpg(server.pid, signal.SIGINT)
        try:
            server.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(server.pid, signal.SIGKILL)
            server.wait()


def run(readme: Path, work: Path, until_first_shaped: bool) -> dict:
    commands = quick_start_commands(readme.read_text())
    if commands[0] != "source .venv/bin/activate":
        raise ValueError("the quick start must begin by activating the venv")
    commands = commands[1:]
    (server_command,) = (c for c in commands if c.startswith(SERVER))
    steps = [c for c in commands if c is not server_command]
    first_shaped = _first_shaped_run(steps)
    if until_first_shaped:
        steps = steps[: first_shaped + 1]
    if work.exists():
        shutil.rmtree(work)
    work.mkdir(parents=True)
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    record: dict = {
        "commit": _git_commit(),
        "started_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "load_average_1min": os.getloadavg()[0],
        "cpus": os.cpu_count(),
        "server": server_command,
        "steps": [],
    }
    t0 = time.monotonic()
    server = _start_server(server_command, env, work)
    record["server_ready_s"] = time.monotonic() - t0
    ready = time.monotonic()
    try:
        for i, command in enumerate(steps):
            print(f"$ {command}", flush=True)
            start = time.monotonic()
            done = subprocess.run(
                command, shell=True, cwd=work, env=env, capture_output=True, text=True
            )
            seconds = time.monotonic() - start
            printed = (done.stdout + done.stderr).splitlines()
            for line in printed:
                print(f"  {line}", flush=True)
            record["steps"].append(
                {
                    "command": command,
                    "seconds": seconds,
                    "exit_code": done.returncode,
                    "printed": printed,
                }
            )
            if done.returncode != 0:
                raise RuntimeError(f"{command!r} exited {done.returncode}")
            if i == first_shaped:
                record["ready_to_first_shaped_move_s"] = time.monotonic() - ready
    finally:
        _stop(server)
    record["total_s"] = time.monotonic() - t0
    return record


def main(argv: list[str] | None = None) -> int:
    # Started as a background job (``make quick-start &``), this process ignores SIGINT and
    # so would the server it starts: the Ctrl-C that stops it would be lost. A handler here
    # is reset to the default in each child.
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    p = argparse.ArgumentParser(description=__doc__.split("\n\n", 1)[0])
    p.add_argument("--readme", type=Path, default=ROOT / "README.md")
    p.add_argument("--out", type=Path, default=ROOT / "out" / "quick-start")
    p.add_argument(
        "--until-first-shaped-move",
        action="store_true",
        help="stop after the first shaped 'tvist run' (about a minute)",
    )
    args = p.parse_args(argv)
    record = run(args.readme, args.out / "work", args.until_first_shaped_move)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "run.json").write_text(json.dumps(record, indent=1) + "\n")
    print(
        f"first shaped move {record.get('ready_to_first_shaped_move_s', float('nan')):.0f} s "
        f"after the server was ready; all {record['total_s']:.0f} s; "
        f"record in {args.out / 'run.json'}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
