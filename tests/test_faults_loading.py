"""A run folder is data: loading one never imports code, and the sizes it names are checked by
arithmetic before memory is spent. Real processes, started in a folder holding a module the
planted task name would import."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from processes import checkout_env, one_error_line, somarm_command

from somarm import run

PLANTED = ("gym:evilcfg:Pendulum-v1", "gym:this:X-v0", "dmc:evilcfg:x-y", "evilcfg:reach2")


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory) -> Path:
    """A small reach2 run, written as `somarm train` writes it."""
    out = tmp_path_factory.mktemp("loading") / "reach2"
    run.write(run.train(run.RunConfig(task="reach2", n_trials=2, n_steps=100, seed=1), progress=False), out,
              figures=False)
    return out


def _planted(run_folder: Path, tmp_path: Path, **changes) -> Path:
    """A copy of the run whose config.json is changed, beside a module that leaves a mark when imported."""
    folder = tmp_path / "run"
    shutil.copytree(run_folder, folder)
    config = json.loads((folder / "config.json").read_text())
    (folder / "config.json").write_text(json.dumps({**config, **changes}))
    (tmp_path / "evilcfg.py").write_text("from pathlib import Path\nPath(__file__).with_name('MARK').touch()\n")
    return folder


def _ran_code(tmp_path: Path, done: subprocess.CompletedProcess) -> bool:
    return (tmp_path / "MARK").exists() or "Beautiful is better than ugly" in done.stdout + done.stderr


@pytest.mark.parametrize("task", PLANTED)
def test_evaluate_of_a_folder_naming_a_module_imports_nothing_and_says_so_in_one_line(run_folder, tmp_path, task):
    folder = _planted(run_folder, tmp_path, task=task)
    done = subprocess.run(somarm_command("evaluate", "run"), capture_output=True, text=True, cwd=tmp_path,
                          env=checkout_env(), timeout=120)
    assert not _ran_code(tmp_path, done)
    one_error_line(done, str(folder.name), "which a file may not name")


@pytest.mark.parametrize("task", PLANTED[:2])
def test_somq_load_of_a_folder_naming_a_module_imports_nothing(run_folder, tmp_path, task):
    _planted(run_folder, tmp_path, task=task)
    code = ("from somarm import SOMQ\ntry:\n    SOMQ.load('run')\nexcept ValueError as exc:\n    print(exc)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path,
                          env=checkout_env(), timeout=120)
    assert not _ran_code(tmp_path, done) and done.returncode == 0, done.stderr
    assert "which a file may not name" in done.stdout and len(done.stdout.strip().splitlines()) == 1


@pytest.mark.parametrize("n_trials", [1_000_000_000, 10**30])
def test_a_config_naming_a_huge_number_of_trials_is_refused_before_memory_is_spent(run_folder, tmp_path, n_trials):
    folder = _planted(run_folder, tmp_path, n_trials=n_trials)
    done = subprocess.run(somarm_command("evaluate", str(folder)), capture_output=True, text=True,
                          env=checkout_env(), timeout=60, preexec_fn=_address_space(1_500_000))
    one_error_line(done, str(folder / "learner.npz"))


def test_train_with_a_billion_trials_is_refused_in_one_line_before_memory_is_spent(tmp_path):
    done = subprocess.run(somarm_command("train", "reach2", "--trials", "1000000000", "--out", str(tmp_path / "r")),
                          capture_output=True, text=True, env=checkout_env(), timeout=60,
                          preexec_fn=_address_space(1_500_000))
    one_error_line(done, "1000000000 trial(s)", "of memory, more than the")
    assert not (tmp_path / "r").exists()


def _address_space(kib: int):
    """A ``preexec_fn`` giving the child ``ulimit -v kib``: building a list of a billion trials fails there."""
    import resource

    def limited():
        resource.setrlimit(resource.RLIMIT_AS, (kib * 1024, resource.RLIM_INFINITY))

    return limited
