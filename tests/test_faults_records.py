"""Damaged seed records of a comparison, on real processes: each is named in one line and its seed trained
again, and what the resumed comparison writes is strict JSON."""

from __future__ import annotations

import json
import subprocess

import pytest
from processes import checkout_env, somarm_command

COMPARE = ("compare", "throw_distance", "--learners", "tabular", "--samples", "200", "--seeds", "1",
           "--observations", "10", "--no-progress", "--resume")


def somarm(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run(somarm_command(*argv), capture_output=True, text=True, env=checkout_env(), timeout=120)


def _damage(record: dict, how: str) -> str:
    if how == "wrong shape":
        record["values"] = [[v] for v in record["values"]]
    elif how == "text":
        record["values"] = ["a lot" for _ in record["values"]]
    elif how == "nan":
        return json.dumps(record).replace(str(record["values"][0]), "NaN", 1)
    elif how == "deep":
        return json.dumps(record)[:-1] + ', "x": ' + "[" * 100_000 + "]" * 100_000 + "}"
    elif how == "a list":
        return "[1, 2]"
    return json.dumps(record)


@pytest.mark.parametrize("how", ["wrong shape", "text", "nan", "deep", "a list"])
def test_a_damaged_seed_record_is_named_and_its_seed_trained_again(tmp_path, how):
    out = tmp_path / "cmp"
    assert somarm(*COMPARE, "--out", str(out)).returncode == 0
    path = out / "seeds" / "tabular-0.json"
    good = json.loads(path.read_text())
    path.write_text(_damage(dict(good), how))
    done = somarm(*COMPARE, "--out", str(out))
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    assert done.stderr.strip().splitlines() == [
        line for line in done.stderr.strip().splitlines() if line.startswith(f"{path} is damaged: ")]
    assert len(done.stderr.strip().splitlines()) == 1 and "training that seed again" in done.stderr
    again = json.loads(path.read_text(), parse_constant=pytest.fail)
    assert again["values"] == good["values"]  # trained again from the same seed: the same scores
    result = json.loads((out / "compare.json").read_text(), parse_constant=pytest.fail)
    assert result["complete"] and [row[0] for row in result["learners"]["tabular"]["error"]] == good["values"]
