"""Shared set-up for the inspector's browser tests (imported explicitly; not a conftest): Debian's
Chromium driven by Playwright (``make browser`` installs it), a ``faultmas run --inspect`` child, and a
recorder the tests put in the page to see, afterwards, everything it showed while the run went on."""
from __future__ import annotations

import os
import re
import time
from pathlib import Path

import pytest

from tests.agents.distributed_fixtures import Proc

CHROMIUM = os.environ.get("FAULTMAS_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_ARGS = ["--no-sandbox", "--headless=new", "--disable-gpu", "--disable-dev-shm-usage",
                 "--disable-background-networking", "--disable-component-update", "--no-first-run",
                 "--disable-sync", "--disable-default-apps"]
DOCS = Path(__file__).resolve().parents[2] / "docs"

# Every 100 ms, what the page shows now (when it changed): the team rows, the chosen agent's beliefs,
# intentions and cycle count, each robot's poses, the timeline's marks.
RECORDER = r"""
() => {
  window.__seen = [];
  let last = "";
  const text = (sel) => [...document.querySelectorAll(sel)].map((e) => e.textContent);
  setInterval(() => {
    const snap = {
      team: [...document.querySelectorAll("#team tbody tr")].map((r) => [r.dataset.agent, r.className]),
      beliefs: text("#beliefs li"),
      intentions: document.querySelector("#intentions").innerText,
      cycles: document.querySelector("#cycles").textContent,
      robots: Object.fromEntries([...document.querySelectorAll("#robots tbody tr")].map(
        (r) => [r.dataset.robot, [r.querySelector(".pose").textContent, r.querySelector(".truth").textContent]])),
      marks: [...document.querySelectorAll("#timeline .mark")].map((m) => [m.dataset.agent, m.dataset.step]),
    };
    const json = JSON.stringify(snap);
    if (json !== last) { last = json; snap.t = performance.now(); window.__seen.push(snap); }
  }, 100);
}
"""


def wait_line(proc: Proc, pattern: str, timeout: float) -> re.Match:
    """The first stdout line of ``proc`` matching ``pattern`` (fails the test after ``timeout``)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        for line in list(proc.out):
            found = re.search(pattern, line)
            if found:
                return found
        if proc.process.poll() is not None:
            break
        time.sleep(0.1)
    pytest.fail(f"no line matching {pattern!r} within {timeout} s; stdout:\n" + "\n".join(proc.out[-30:])
                + "\nstderr:\n" + "\n".join(proc.err[-30:]))


def run_inspected(*args: str) -> tuple[Proc, str]:
    """``faultmas run --inspect ARGS`` on a free loopback port; the child and the page's URL."""
    proc = Proc(["run", "--inspect", "--listen", "127.0.0.1:0", *args])
    url = wait_line(proc, r"inspector at (http://127\.0\.0\.1:\d+/)", 60).group(1)
    return proc, url


def launch_browser(playwright):
    if not Path(CHROMIUM).exists():
        pytest.fail(f"{CHROMIUM} is missing: `make browser` installs Debian's chromium (as root)")
    return playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True)


def open_page(browser, url: str, agent: str | None = None):
    page = browser.new_page(viewport={"width": 1500, "height": 1050})
    page.goto(url + (f"#agent={agent}" if agent else ""))
    page.evaluate(RECORDER)
    return page
