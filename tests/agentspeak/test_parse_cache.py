"""Parsed files kept between runs (agentspeak/parse_cache.py, issue 23 §1): a file run again unchanged skips the
parser and Lark, and gives exactly what parsing gives; anything that could make an entry wrong (the text, the
grammar or the interpreter's code, the registered functions) makes it miss. The runs that matter are fresh
processes (another PYTHONHASHSEED each: a hash kept from one process is wrong in the next)."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

from agentspeak import parse_cache
from agentspeak.parser import parse_program

PROGRAM = """\
items([3, 1, 2]).
empty([]).
p(a)[source(self), note(x)].
{ register_function("my.twice", 1, "twice") }
twice(X, Y) :- Y = X * 2.
!start.
@go[atomic] +!start : items(L) & empty([]) <-
    .sort(L, S);
    ?p(a)[note(N)];
    X = my.twice(math.abs(-4));
    .print(S, " ", N, " ", X, " ", .length([]));
    !a.
+!a <- !s(1); !s(2). {
    +!s(1) <- .print(inner).
}
+!s(N) <- .print(outer, N).
"""
EXPECTED = "[prog] [1,2,3] x 8 0\n[prog] inner\n[prog] outer2"


def _run(argv: list[str], cache: Path, seed: str, watched: tuple[str, ...] = ("lark", "agentspeak.parser")):
    """``faultmas ARGV`` in a new interpreter: (exit status, stdout, which ``watched`` modules it imported)."""
    code = ("import contextlib, io, json, sys\n"
            "from agents.cli import main\n"
            "out = io.StringIO()\n"
            "with contextlib.redirect_stdout(out):\n"
            f"    status = main({argv!r})\n"
            f"print(json.dumps([status, out.getvalue(), sorted(m for m in {watched!r} if m in sys.modules)]))\n")
    env = {**os.environ, "FAULTMAS_CACHE_DIR": str(cache), "PYTHONHASHSEED": seed}
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.splitlines()[-1])


def test_a_file_run_again_skips_the_parser_and_prints_the_same_and_an_edited_one_is_parsed(tmp_path: Path) -> None:
    source = tmp_path / "prog.asl"
    source.write_text(PROGRAM)
    cache = tmp_path / "cache"
    status, out, imported = _run(["asl", "run", str(source)], cache, "1")
    assert (status, out.strip(), imported) == (0, EXPECTED, ["agentspeak.parser", "lark"])
    assert len(list((cache / parse_cache.SUBDIRECTORY).glob("program-prog.asl-*.pickle"))) == 1
    status, out, imported = _run(["asl", "run", str(source)], cache, "2")      # another hash seed
    assert (status, out.strip(), imported) == (0, EXPECTED, [])
    source.write_text(PROGRAM.replace('" ", X,', '" ", X + 1,'))
    status, out, imported = _run(["asl", "run", str(source)], cache, "3")
    assert (status, out.strip(), imported) == (0, EXPECTED.replace(" 8 ", " 9 "), ["agentspeak.parser", "lark"])


def test_a_project_file_run_again_needs_no_lark_and_finds_its_sources_anew(tmp_path: Path) -> None:
    (tmp_path / "prog.asl").write_text(PROGRAM)
    project = tmp_path / "team.mas2j"
    project.write_text('MAS team {\n    agents:\n        prog prog.asl;\n}\n')
    cache = tmp_path / "cache"
    assert _run(["mas", "run", str(project)], cache, "1")[:2] == [0, EXPECTED + "\n"]
    assert _run(["mas", "run", str(project)], cache, "2") == [0, EXPECTED + "\n", []]
    moved = tmp_path / "elsewhere"                      # the same project text in another folder
    moved.mkdir()
    shutil.copy(project, moved / "team.mas2j")
    (moved / "prog.asl").write_text(PROGRAM.replace('" ", X,', '" ", X - 1,'))
    assert _run(["mas", "run", str(moved / "team.mas2j")], cache, "3")[:2] == [0, EXPECTED.replace(" 8 ", " 7 ") + "\n"]


def test_a_loaded_program_is_the_parsed_one_in_this_process(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("FAULTMAS_CACHE_DIR", str(tmp_path))
    source = str(tmp_path / "prog.asl")
    parsed = parse_program(PROGRAM, source)
    parse_cache._PROGRAMS.clear()
    parse_cache.cached_program(PROGRAM, source)                  # parsed and stored
    parse_cache._PROGRAMS.clear()
    monkeypatch.setattr(parse_cache, "_parse", lambda *a: (_ for _ in ()).throw(AssertionError("parsed again")))
    loaded = parse_cache.cached_program(PROGRAM, source)         # from the file
    assert [str(p) for p in loaded.plans] == [str(p) for p in parsed.plans]
    assert [str(r.head) for r in loaded.rules] == [str(r.head) for r in parsed.rules]
    assert loaded.beliefs == parsed.beliefs
    assert [hash(b) for b in loaded.beliefs] == [hash(b) for b in parsed.beliefs]
    from agentspeak.terms import NIL
    assert loaded.beliefs[1].args[0] is NIL                      # `t is NIL` tests hold
    assert loaded.plans[0].atomic
    assert [len(p.sub_plans) for p in loaded.plans] == [len(p.sub_plans) for p in parsed.plans] == [0, 1, 0]


def test_kept_literals_hash_as_the_loading_process_does(tmp_path: Path, monkeypatch) -> None:
    """String hashes differ between processes: a literal must not bring its hash from the one that kept it."""
    monkeypatch.setenv("FAULTMAS_CACHE_DIR", str(tmp_path))
    source = str(tmp_path / "prog.asl")
    parse_cache._PROGRAMS.clear()
    {hash(b) for b in parse_program(PROGRAM, source).beliefs}   # hashed here (the parser shares these terms) ...
    parse_cache.cached_program(PROGRAM, source)                  # ... then kept by this process
    code = ("import sys\n"
            "from agentspeak import parse_cache\n"
            "from agentspeak.parser import parse_program\n"
            f"text, source = {PROGRAM!r}, {source!r}\n"
            "parse_cache._parse = None\n"                          # loaded, or this fails
            "loaded = parse_cache.cached_program(text, source)\n"
            "fresh = set(parse_program(text, source + '.fresh').beliefs)\n"
            "print([b in fresh for b in loaded.beliefs])\n")
    for seed in ("7", "8"):
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                              env={**os.environ, "PYTHONHASHSEED": seed})
        assert done.stdout.strip() == "[True, True, True]", done.stderr


def test_anything_an_entry_depends_on_makes_it_miss(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("FAULTMAS_CACHE_DIR", str(tmp_path))
    calls = []

    def parse():
        calls.append(1)
        return {"parsed": len(calls)}

    assert parse_cache.cached("t", "text", "/f.asl", (), parse) == {"parsed": 1}
    assert parse_cache.cached("t", "text", "/f.asl", (), parse) == {"parsed": 1}          # kept
    assert parse_cache.cached("t", "text!", "/f.asl", (), parse) == {"parsed": 2}         # the text
    assert parse_cache.cached("t", "text", "/g.asl", (), parse) == {"parsed": 3}          # the file
    assert parse_cache.cached("t", "text", "/f.asl", ("x",), parse) == {"parsed": 4}      # what else it read
    monkeypatch.setattr(parse_cache, "_code_key", ("another interpreter",))
    assert parse_cache.cached("t", "text", "/f.asl", (), parse) == {"parsed": 5}          # the code
    assert parse_cache.cached("t", "text", "<string>", (), parse) == {"parsed": 6}        # not a file: never kept
    assert parse_cache.cached("t", "text", "<string>", (), parse) == {"parsed": 7}


def test_an_edited_grammar_changes_the_code_key(tmp_path: Path) -> None:
    """What another branch's grammar change does to the kept entries: they all miss (no build step to rerun)."""
    package = Path(parse_cache.__file__).parent
    copy = tmp_path / "agentspeak"
    shutil.copytree(package, copy, ignore=shutil.ignore_patterns("__pycache__", "*.so"))
    before = parse_cache.package_files(str(copy))
    assert ("agentspeak.lark", (package / "agentspeak.lark").stat().st_size) in {f[:2] for f in before}
    grammar = copy / "agentspeak.lark"
    grammar.write_text(grammar.read_text() + "\n// a new rule on branch jlang\n")
    assert parse_cache.package_files(str(copy)) != before


def test_a_damaged_entry_or_an_unwritable_directory_only_costs_the_parse(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("FAULTMAS_CACHE_DIR", str(tmp_path))
    parse_cache.cached("t", "text", "/f.asl", (), lambda: "first")
    [entry] = (tmp_path / parse_cache.SUBDIRECTORY).iterdir()
    entry.write_bytes(entry.read_bytes()[:-5])
    assert parse_cache.cached("t", "text", "/f.asl", (), lambda: "again") == "again"
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    monkeypatch.setenv("FAULTMAS_CACHE_DIR", str(blocker))
    assert parse_cache.cached("t", "text", "/f.asl", (), lambda: "parsed") == "parsed"


def test_the_directory_keeps_at_most_max_entries(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("FAULTMAS_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(parse_cache, "MAX_ENTRIES", 3)
    for i in range(6):
        parse_cache.cached("t", f"text {i}", "/f.asl", (), lambda: i)
    assert len(list((tmp_path / parse_cache.SUBDIRECTORY).iterdir())) == 3
