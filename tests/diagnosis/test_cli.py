"""``faultmas diagnose``: the JSON contract used by the acceptance checks, and errors on bad input."""
from __future__ import annotations

import json

from agents.cli import main

C17_OBS = {"G1gat": 1, "G2gat": 1, "G3gat": 1, "G6gat": 1, "G7gat": 1, "G22gat": 1, "G23gat": 1}


def test_json_output_for_a_netlist(data_dir, write, capsys):
    obs = write("obs.json", json.dumps(C17_OBS))
    assert main(["diagnose", str(data_dir / "c17.bench"), "--obs", str(obs), "--max-card", "2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {"diagnoses", "min_cardinality", "complete", "seconds"}
    assert out["min_cardinality"] == 1 and out["complete"] is True
    assert ["G23gat"] in out["diagnoses"] and all(len(d) <= 2 for d in out["diagnoses"])


def test_min_card_only_lists_just_the_smallest(data_dir, write, capsys):
    obs = write("obs.json", json.dumps(C17_OBS))
    assert main(["diagnose", str(data_dir / "c17.bench"), "--obs", str(obs), "--min-card-only", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["diagnoses"] and all(len(d) == out["min_cardinality"] == 1 for d in out["diagnoses"])


def test_yaml_model_text_output(repo, write, capsys):
    obs = write("obs.json", json.dumps({"commanded_forward": True, "encoders_report_motion": True,
                                         "encoders_report_straight": False, "left_over_current": False,
                                         "helper_found_robot": True, "helper_saw_veer_left": True}))
    assert main(["diagnose", str(repo / "plans" / "turtlebot_hardware.yaml"), "--obs", str(obs)]) == 0
    assert capsys.readouterr().out.strip() == "{left_motor}"


def test_bad_observation_files_exit_2_naming_the_file(data_dir, write, capsys):
    for text, fragment in [("[1, 2]", "must be a JSON object"), ('{"G1gat": 2}', "must be 0, 1, true or false"),
                           ('{"G1gat": 1,', "not JSON"), ('{"nope": 1}', "unknown observation 'nope'")]:
        obs = write("obs.json", text)
        assert main(["diagnose", str(data_dir / "c17.bench"), "--obs", str(obs)]) == 2
        err = capsys.readouterr().err
        assert fragment in err and ("obs.json" in err or "c17.bench" in err)


def test_with_lark_parser_in_place_of_lark_1_a_netlist_is_diagnosed_and_a_yaml_model_refused_in_one_line(
        data_dir, repo, write, tmp_path):
    """``diagnose`` leaves the Lark check to what parses with Lark (issue 23: start-up): a ``.bench`` netlist needs
    no Lark and is diagnosed whichever ``lark`` won; a ``.yaml`` model's formulas are refused with the fix."""
    import os
    import subprocess
    import sys

    fake = tmp_path / "site" / "lark"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text('__version__ = "0.12.0"\n')   # what lark-parser 0.12 installs as ``lark``
    env = {**os.environ, "PYTHONPATH": str(fake.parent), "FAULTMAS_CACHE_DIR": str(tmp_path / "cache")}
    obs = write("obs.json", json.dumps(C17_OBS))
    yaml_obs = write("yaml_obs.json", json.dumps({"commanded_forward": True}))

    def diagnose(model, observations):
        return subprocess.run([sys.executable, "-m", "agents", "diagnose", str(model), "--obs", str(observations),
                               "--json"], capture_output=True, text=True, env=env, timeout=120, cwd=tmp_path)

    netlist = diagnose(data_dir / "c17.bench", obs)
    assert netlist.returncode == 0, netlist.stderr
    assert ["G23gat"] in json.loads(netlist.stdout)["diagnoses"]
    refused = diagnose(repo / "plans" / "turtlebot_hardware.yaml", yaml_obs)
    assert refused.returncode == 2 and "Traceback" not in refused.stderr
    [line] = refused.stderr.strip().splitlines()
    assert "0.12.0" in line and "--force-reinstall --no-deps 'lark>=1.2,<2'" in line
