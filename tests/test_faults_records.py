"""Damaged seed records of a comparison, on real processes: each is named in one line and its seed trained
again, and what the resumed comparison writes is strict JSON."""

from __future__ import annotations

import json
import subprocess

import numpy as np
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


HOW = ["wrong shape", "text", "nan", "deep", "a list"]


def test_a_damaged_seed_record_is_named_and_its_seed_trained_again(tmp_path):
    out = tmp_path / "cmp"
    argv = [*COMPARE, "--out", str(out)]
    argv[argv.index("--seeds") + 1] = str(len(HOW))
    assert somarm(*argv).returncode == 0
    good = {}
    for seed, how in enumerate(HOW):  # each seed's record damaged its own way
        path = out / "seeds" / f"tabular-{seed}.json"
        good[path] = json.loads(path.read_text())
        path.write_text(_damage(dict(good[path]), how))
    done = somarm(*argv)
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == len(HOW)  # one line each, naming its file
    for line, path in zip(lines, good, strict=True):
        assert line.startswith(f"{path} is damaged: ") and line.endswith("; training that seed again"), line
    for path, record in good.items():
        again = json.loads(path.read_text(), parse_constant=pytest.fail)
        assert again["values"] == record["values"]  # trained again from the same seed: the same scores
    result = json.loads((out / "compare.json").read_text(), parse_constant=pytest.fail)
    assert result["complete"] and np.array(result["learners"]["tabular"]["error"]).T.tolist() == [
        record["values"] for record in good.values()]
