"""Shared set-up for the distributed-agent tests (imported explicitly; not a conftest): AgentSpeak
projects written to a temporary folder, ``faultmas`` child processes with their output read by
threads (a child must never block on a full pipe), and waiting for lines."""
from __future__ import annotations

import os
import subprocess
import sys
import threading
from pathlib import Path
from typing import Sequence

REPO = Path(__file__).resolve().parents[2]

# Every performative between three agent kinds; askOne with a timeout; a broadcast to 3 agents.
ALICE = r'''
!start.

+!start <-
    .send(bob, tell, [price(apple, 3), price(pear, 5)]);
    .send(bob, askOne, price(apple, P), A1);
    .print("askOne ", A1);
    .send(bob, askOne, price(kiwi, _), A2);
    .print("askOne unknown ", A2);
    .send(bob, askAll, price(_, _), A3);
    .print("askAll ", A3);
    .send(bob, untell, price(pear, 5));
    .send(bob, askAll, price(F, _), A4);
    .print("after untell ", A4);
    .send(bob, tellHow, {@dbl +!double(X) <- .print("double ", X * 2)});
    .send(bob, achieve, double(21));
    .send(bob, askHow, "+!double(_)", H);
    .print("askHow ", H);
    .send(bob, untellHow, dbl);
    .send(bob, askHow, "+!double(_)", H2);
    .print("askHow after untellHow ", H2);
    .send(bob, achieve, work);
    .send(bob, unachieve, work);
    .send(bob, signal, alarm(7));
    .send(carol1, askOne, slow(S), A5, 300);
    .print("askOne timeout ", A5);
    .send([bob, carol1, carol2], tell, note("a string, with \"quotes\"", -2.5, [x, "y"]));
    .broadcast(tell, hello(alice));
    .all_names(L);
    .print("names ", L).
'''

BOB = r'''
+price(F, P)[source(S)] <- .print("told price ", F, " ", P, " by ", S).
-price(F, P)[source(S)] <- .print("untold price ", F, " by ", S).
+!work <- .wait(1000); .print("work finished").
+alarm(N)[source(S)] <- .print("signal ", N, " from ", S).
+hello(X)[source(S)] <- .print("hello from ", S).
+note(T, N, L)[source(S)] <- .print("note ", T, " ", N, " ", L, " from ", S).
'''

CAROL = r'''
+?slow(X) <- .wait(800); X = 1.
+hello(X)[source(S)] <- .print("hello from ", S).
+note(T, N, L)[source(S)] <- .print("note ", T, " ", N, " ", L, " from ", S).
'''

ACTS_MAS2J = "MAS acts {\n    agents:\n        alice;\n        bob;\n        carol #2;\n}\n"

# Presence, trust and robustness: watcher is told plans by friend (declared) and intruder (not
# declared); pinger keeps an askOne conversation with watcher going until a tester says enough.
WATCHER = r'''
+agent_alive(N) <- .print("alive ", N).
-agent_alive(N) <- .print("gone ", N).
+?echo(N, X) <- X = N.
+done_by(X)[source(S)] <- .print("done by ", S).
'''

FRIEND = r'''
+agent_alive(watcher) <- .send(watcher, tellHow, {+!greet <- .print("greeted")}); .send(watcher, achieve, greet).
'''

INTRUDER = r'''
+agent_alive(watcher) <-
    .send(watcher, tellHow, {+!hack <- .print("hacked")});
    .send(watcher, achieve, hack);
    .send(watcher, tell, done_by(intruder)).
'''

PINGER = r'''
+agent_alive(watcher) : not started <- +started; .print("conversation started"); !ping(1).
+!ping(N) : enough[source(_)] <- .print("conversation done ", N - 1).
+!ping(N) <-
    .send(watcher, askOne, echo(N, X), A, 10000);
    if (A == timeout) { .print("lost answer ", N) } else { A = echo(_, M)[source(watcher)]; if (M \== N) { .print("bad answer ", A) } };
    !ping(N + 1).
'''

TEAM_MAS2J = "MAS team {\n    agents:\n        watcher;\n        friend;\n        pinger;\n}\n"


def write_files(folder: Path, files: dict[str, str]) -> Path:
    """Write ``name -> text`` into ``folder`` (made if missing); return the folder."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (folder / name).write_text(text)
    return folder


class Proc:
    """A ``python -m agents ...`` child; stdout and stderr lines collected by reader threads."""

    def __init__(self, args: Sequence[str], cwd: Path | None = None) -> None:
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        self.process = subprocess.Popen([sys.executable, "-m", "agents", *args], cwd=cwd or REPO, env=env, text=True,
                                        stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        self.out: list[str] = []
        self.err: list[str] = []
        self._changed = threading.Condition()
        self._readers = [threading.Thread(target=self._read, args=(stream, lines), daemon=True)
                         for stream, lines in ((self.process.stdout, self.out), (self.process.stderr, self.err))]
        for reader in self._readers:
            reader.start()

    def _read(self, stream, lines: list[str]) -> None:
        for line in stream:
            with self._changed:
                lines.append(line.rstrip("\n"))
                self._changed.notify_all()
        with self._changed:
            self._changed.notify_all()

    def wait_out(self, line: str, timeout: float = 30.0) -> bool:
        """True once ``line`` was printed on stdout (False after ``timeout`` or if the child ended)."""
        with self._changed:
            return self._changed.wait_for(lambda: line in self.out or self.process.poll() is not None
                                          and not any(r.is_alive() for r in self._readers), timeout) and line in self.out

    def finish(self, timeout: float = 60.0) -> int:
        """Wait for the exit code and the last output lines."""
        try:
            code = self.process.wait(timeout)
        except subprocess.TimeoutExpired:
            self.process.kill()
            code = self.process.wait()
        for reader in self._readers:
            reader.join(10)
        return code

    def stop(self, signum: int = 15, timeout: float = 10.0) -> int:
        if self.process.poll() is None:
            self.process.send_signal(signum)
        return self.finish(timeout)


def agent_run(folder: Path, name: str, mas: str, connect: str, *extra: str) -> Proc:
    """``faultmas agent run <folder>/<name>.asl --name <name> --mas <mas> --connect <connect>``."""
    return Proc(["agent", "run", str(folder / f"{name}.asl"), "--name", name, "--mas", mas,
                 "--connect", connect, *extra])


def mas_run(project: Path, *extra: str, cwd: Path | None = None) -> Proc:
    """``faultmas mas run PROJECT ...`` (from ``cwd``: the repository by default)."""
    return Proc(["mas", "run", str(project), *extra], cwd=cwd)
