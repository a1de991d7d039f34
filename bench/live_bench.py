"""The live page's cost to the controller: DALA's corridor mission in real time, with the page closed, then open.

    python bench/live_bench.py [--runs N] [--screenshot FILE [--width PX] [--module NAME] [--open-only]]
    (needs gen/dala, Debian's chromium, Playwright)

Each run is ``genom2bip mission descriptions/dala/missions/corridor.yaml --view`` in a process of its own (real
time: tasks of 25 to 100 ms).  With the page open, headless Chromium (another process, as an operator's browser
is) shows ``/live/`` for the whole mission.  The bench reads ``GET /tasks`` once a second in both cases (the same
load with the page closed or open) and prints, per task, the periods run, the periods missed, the overruns and the
lateness at the mission's end, and the CPU time of the mission's process and of the browser; with the page open,
the page's own count of updates per second (events applied to the page), read once a second from
``window.live.stats``.  With ``--runs N`` the order alternates (closed then open, open then closed...).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
MISSION = ROOT / "descriptions" / "dala" / "missions" / "corridor.yaml"


def start_mission(out: Path) -> tuple[subprocess.Popen, str]:
    """The mission with ``--view`` in a process of its own; returns it and its page's address once printed."""
    proc = subprocess.Popen([sys.executable, "-m", "genom2bip", "mission", str(MISSION), "--view", "--quiet",
                             "--out", str(out)], cwd=ROOT, stdout=subprocess.PIPE, text=True,
                            env=os.environ | {"PYTHONUNBUFFERED": "1"})
    for line in proc.stdout:
        if line.startswith("live view: "):
            return proc, line.split()[2].rsplit("/live/", 1)[0]
    raise SystemExit(f"the mission ended without serving its page (exit {proc.wait()})")


def cpu_seconds(pids: list[int]) -> float:
    """User + system CPU of these processes so far (/proc), 0 for one that has gone."""
    tick = os.sysconf("SC_CLK_TCK")
    total = 0
    for pid in pids:
        try:
            fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        total += int(fields[11]) + int(fields[12])
    return total / tick


def descendants(pid: int) -> list[int]:
    """Every process under ``pid`` (Playwright's driver and the browser it started)."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(ppid, []).append(int(entry.name))
    out, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            out.append(child)
            todo.append(child)
    return out


def read_tasks(url: str, pid: int, last: dict, stop: threading.Event) -> None:
    """GET /tasks once a second until the server goes; ``last`` keeps the newest answer and the mission's CPU."""
    while not stop.is_set():
        try:
            with urllib.request.urlopen(url + "/tasks", timeout=5) as answer:
                last["tasks"] = json.loads(answer.read())
            last["cpu"] = cpu_seconds([pid])
        except OSError:
            return
        stop.wait(1.0)


def one_run(page_open: bool, screenshot: Path | None, width: int = 1500, module: str | None = None) -> dict:
    """One corridor mission; the tasks at its end and, page open, the page's updates per second."""
    with tempfile.TemporaryDirectory() as out:
        proc, url = start_mission(Path(out))
        last: dict = {}
        stop = threading.Event()
        reader = threading.Thread(target=read_tasks, args=(url, proc.pid, last, stop), daemon=True)
        reader.start()
        rates: list[int] = []
        events = 0
        browser_cpu = 0.0
        started = time.perf_counter()
        if page_open:
            from playwright.sync_api import sync_playwright

            from browserkit import launch

            with sync_playwright() as playwright:
                browser = launch(playwright)
                page = browser.new_page(viewport={"width": width, "height": 1100})
                page.goto(url + "/live/")
                page.wait_for_selector('#stream[data-status="open"]', timeout=60_000)
                shot_at = time.perf_counter() + 25
                while proc.poll() is None:
                    try:
                        stats = page.evaluate("({rate: live.stats.rate, events: live.stats.events,"
                                              " open: live.streamOpen})")
                    except Exception:  # noqa: BLE001 - the page went with the server
                        break
                    if not stats["open"]:
                        break
                    rates.append(stats["rate"])
                    events = stats["events"]
                    mission = {proc.pid, *descendants(proc.pid)}
                    browser_cpu = cpu_seconds([p for p in descendants(os.getpid()) if p not in mission])
                    if screenshot is not None and time.perf_counter() > shot_at:
                        if module:  # its view open, as an operator who clicked it sees it
                            page.click(f'#level g.node.module:has(title:text-is("{module}"))')
                            page.wait_for_selector(f'#module g.node:has(title:text-is("{module}.requests"))')
                        # the whole page in the viewport: what is off the screen is not drawn (docs/live.md)
                        page.set_viewport_size({"width": width, "height": page.evaluate("document.body.scrollHeight")})
                        page.wait_for_timeout(1500)
                        page.screenshot(path=str(screenshot))
                        page.set_viewport_size({"width": width, "height": 1100})
                        screenshot = None
                    page.wait_for_timeout(1000)
                browser.close()
        proc.wait()
        stop.set()
        wall = time.perf_counter() - started
    return {"tasks": last.get("tasks", []), "rates": rates, "events": events, "wall": wall, "exit": proc.returncode,
            "cpu": last.get("cpu", 0.0), "browser_cpu": browser_cpu, "load": os.getloadavg()[0]}


def show(label: str, run: dict) -> None:
    print(f"page {label}: mission exit {run['exit']}, {run['wall']:.1f} s wall, mission process {run['cpu']:.1f} s CPU"
          + (f", browser {run['browser_cpu']:.1f} s CPU" if run["rates"] else "")
          + f"; load average {run['load']:.1f} at the end")
    for t in run["tasks"]:
        lat = t["lateness_ms"]
        print(f"  {t['task']:<22} {t['period_ms']:>6.0f} ms  periods {t['periods']:>5}  missed {t['missed']:>3}  "
              f"overruns {t['overruns']:>3}  lateness p50 {lat['p50']} p99 {lat['p99']} max {lat['max']} ms")
    total = sum(t["missed"] for t in run["tasks"])
    periods = sum(t["periods"] for t in run["tasks"])
    print(f"  missed periods: {total} of {periods}")
    if run["rates"]:
        steady = run["rates"][2:-1] or run["rates"]  # the first seconds load the page
        print(f"  page updates/s: median {statistics.median(steady):.0f}, min {min(steady)}, max {max(steady)} "
              f"({len(steady)} one-second readings); events applied: {run['events']} "
              f"({run['events'] / max(run['wall'], 1e-9):.0f}/s)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1, help="runs of each (default 1)")
    parser.add_argument("--screenshot", type=Path, help="a full-page screenshot of the first open run")
    parser.add_argument("--width", type=int, default=1500, help="the browser's width in px (default 1500)")
    parser.add_argument("--module", metavar="NAME", help="open this module's view before the screenshot")
    parser.add_argument("--open-only", action="store_true", help="only runs with the page open")
    args = parser.parse_args()
    from browserkit import chromium_path

    if chromium_path() is None:
        raise SystemExit("no Chromium: apt-get install chromium (or GENOM2BIP_CHROMIUM=/path/to/chromium)")
    for i in range(args.runs):  # the order alternates, so that a change of the machine's load favours neither
        for page_open in ((True,) if args.open_only else (False, True) if i % 2 == 0 else (True, False)):
            if page_open:
                show("open", one_run(True, args.screenshot if i == 0 else None, args.width, args.module))
            else:
                show("closed", one_run(False, None))


if __name__ == "__main__":
    main()
