"""Grammar tables built once and kept by grammar digest; a replaced Lark 1.x refused with the fix (issue 23)."""
from __future__ import annotations

import os
import types
from pathlib import Path

import pytest

from agentspeak import lark_loader

GRAMMAR = 'start: WORD+\n%import common.WORD\n%import common.WS\n%ignore WS\n'


def test_tables_are_built_once_then_loaded(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv(lark_loader.CACHE_ENV, str(tmp_path / "cache"))
    grammar = tmp_path / "words.lark"
    grammar.write_text(GRAMMAR)
    first = lark_loader.lalr_parser(grammar)
    [table] = (tmp_path / "cache").iterdir()
    assert table.name.startswith("words-")
    stamp = table.stat().st_mtime_ns
    second = lark_loader.lalr_parser(grammar)
    assert table.stat().st_mtime_ns == stamp                  # loaded, not written again
    assert len(second.parse("a b c").children) == len(first.parse("a b c").children) == 3


def test_an_edited_grammar_gets_new_tables_never_stale_ones(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv(lark_loader.CACHE_ENV, str(tmp_path / "cache"))
    grammar = tmp_path / "words.lark"
    grammar.write_text(GRAMMAR)
    lark_loader.lalr_parser(grammar).parse("a b")
    grammar.write_text(GRAMMAR.replace("WORD+", "WORD+ \";\""))      # a grammar change on another branch
    edited = lark_loader.lalr_parser(grammar)
    assert len(list((tmp_path / "cache").iterdir())) == 2
    assert len(edited.parse("a b;").children) == 2
    with pytest.raises(Exception):
        edited.parse("a b")                                          # the old grammar's language is gone


def test_a_cache_directory_that_cannot_be_written_only_costs_time(tmp_path: Path, monkeypatch) -> None:
    blocker = tmp_path / "not-a-directory"
    blocker.write_text("")
    monkeypatch.setenv(lark_loader.CACHE_ENV, str(blocker / "cache"))
    grammar = tmp_path / "words.lark"
    grammar.write_text(GRAMMAR)
    assert len(lark_loader.lalr_parser(grammar).parse("x y").children) == 2


def test_the_project_grammars_go_through_the_cache(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv(lark_loader.CACHE_ENV, str(tmp_path))
    for name in ("agentspeak.lark", "mas2j.lark"):
        lark_loader.lalr_parser(Path(lark_loader.__file__).with_name(name), maybe_placeholders=True)
    from diagnosis import formula
    lark_loader.lalr_parser(Path(formula.__file__).with_name("formula.lark"))
    assert sorted(p.name.split("-")[0] for p in tmp_path.iterdir()) == ["agentspeak", "formula", "mas2j"]


def test_lark_parser_0_12_in_place_of_lark_1_is_refused_with_the_fix(monkeypatch) -> None:
    monkeypatch.setitem(__import__("sys").modules, "lark", types.SimpleNamespace(__version__="0.12.0"))
    with pytest.raises(lark_loader.WrongLarkError) as refused:
        lark_loader.require_lark_1()
    message = str(refused.value)
    assert "0.12.0" in message and "\n" not in message
    assert message.endswith("-m pip install --force-reinstall --no-deps 'lark>=1.2,<2'")
    assert isinstance(refused.value, ImportError)


def test_lark_1_passes(monkeypatch) -> None:
    lark_loader.require_lark_1()
