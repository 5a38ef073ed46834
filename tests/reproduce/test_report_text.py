"""REPORT.md reads right: links that hold from its own folder, sentences built from the run's own numbers,
and legends beside the curves rather than on them."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import somarm
from somarm.reproduce import more_inputs, neighbourhood_q, runner
from somarm.reproduce.report import Claim

#: reach20 and delayed_reward train one trial in quick mode (a count of one) and delayed_reward's
#: greedy episodes there never reach the goal (a step count that is "never"); four_goals moves its
#: goals at a different step in quick mode than at full size.
PARTS = ["reach20", "four_goals", "delayed_reward"]
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")


def _reproduce(cwd: Path, *more: str) -> str:
    """``somarm reproduce --quick --out report`` run in ``cwd`` (a relative --out); its stdout."""
    path = os.pathsep.join(p for p in (str(Path(somarm.__file__).parents[1]), os.environ.get("PYTHONPATH")) if p)
    done = subprocess.run(
        [sys.executable, "-m", "somarm.cli", "reproduce", "--quick", "--no-progress", "--out", "report",
         "--only", *PARTS, *more],
        cwd=cwd, capture_output=True, text=True, timeout=600,
        env={**os.environ, "MUJOCO_GL": "disable", "PYTHONPATH": path},
    )
    assert done.returncode == 0, done.stderr
    return done.stdout


@pytest.fixture(scope="module")
def reports(tmp_path_factory) -> dict[str, tuple[Path, str, str]]:
    """A quick report written with a relative --out, then one forced over it (written into a staging
    folder and moved in): for each, (its folder, REPORT.md's text, what the command printed)."""
    cwd = tmp_path_factory.mktemp("cwd")
    folder = cwd / "report"
    printed = _reproduce(cwd)
    first = (folder, (folder / "REPORT.md").read_text(), printed)
    printed = _reproduce(cwd, "--force")  # the same figures, by the same names
    return {"relative --out": first, "--force": (folder, (folder / "REPORT.md").read_text(), printed)}


@pytest.mark.parametrize("run", ["relative --out", "--force"])
def test_every_link_in_the_report_resolves_from_its_own_folder(reports, run):
    folder, text, _ = reports[run]
    links = LINK.findall(text)
    assert len(links) >= 5, links
    for link in links:
        assert not Path(link).is_absolute() and ".somarm" not in link and not link.startswith("report/"), link
        assert (folder / link).is_file(), f"{link} does not resolve from {folder}"


@pytest.mark.parametrize("run", ["relative --out", "--force"])
def test_the_printed_report_path_is_where_the_report_ends_up(reports, run):
    _, _, printed = reports[run]
    assert re.search(r"^report: report/REPORT\.md \(", printed, re.M), printed
    assert ".somarm" not in printed


def test_sentences_built_from_counts_read_as_english(reports):
    _, text, _ = reports["--force"]
    assert not re.search(r"(?<![\d.,])1 (trial|start|seed|step|throw|episode)s\b", text), \
        re.findall(r".{40}(?<![\d.,])1 [a-z]+s\b.{20}", text)
    assert "in never" not in text and "never steps" not in text
    assert "(s)" not in text


def test_four_goals_header_and_body_name_the_same_move_step(reports):
    _, text, _ = reports["--force"]
    part = text.split("## Figs. 13-15")[1].split("\n## ")[0]
    steps = re.findall(r"moved at t = ([\d,]+)", part)
    assert len(steps) >= 2 and len(set(steps)) == 1, steps  # the header and the choices
    assert steps[0] != "20,000"  # the full-size step, not this quick run's


def test_a_number_no_seed_has_gets_no_range_over_seeds():
    never = [(seed, Claim("c", "m", False, values={"mean length": float("nan")})) for seed in (0, 1)]
    merged = Claim("c", "m", False, values={"mean length": float("nan")}, per_seed=never)
    assert merged.spread() == "mean length: never, never"
    some = [(0, Claim("c", "m", True, values={"x": 2.0})), (1, Claim("c", "m", False, values={"x": float("nan")}))]
    assert "range 2 to 2" in Claim("c", "m", None, values={"x": 2.0}, per_seed=some).spread()


def test_the_legends_of_figs_24_and_25_lie_outside_every_axes(tmp_path, monkeypatch):
    drawn = []
    for module in (neighbourhood_q, more_inputs):
        original = module.save
        monkeypatch.setattr(module, "save", lambda ctx, fig, name, _save=original, **kw: (
            drawn.append((name, _legend_overlaps(fig))), _save(ctx, fig, name, **kw))[1])
    assert runner.reproduce(tmp_path, quick=True, only=["neighbourhood_q", "more_inputs"], progress=False) == 0
    assert [name for name, _ in drawn] == ["fig24_neighbourhood_q.png", "fig25_more_inputs.png"]
    for name, (n_legends, overlaps) in drawn:
        assert n_legends >= 1 and not overlaps, (name, overlaps)


def _legend_overlaps(fig) -> tuple[int, list[str]]:
    """How many legends the figure's axes hold, and those whose box overlaps an axes' plotting area."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    overlaps = [f"{legend.get_texts()[0].get_text()!r} over {ax.get_title()!r}" for legend in legends
                for ax in fig.axes if legend.get_window_extent(renderer).overlaps(ax.get_window_extent(renderer))]
    return len(legends), overlaps


@pytest.mark.parametrize("failed", [[], [0], [0, 2], [0, 1, 2, 3]])
def test_the_edge_sentence_of_fig_8_reads_at_any_count_of_failed_trials(failed):
    import numpy as np

    from somarm.reproduce.reach2 import _edge_text

    mask = np.zeros(4, bool)
    mask[failed] = True
    edge = np.where(mask, 0.95, 0.1)
    edge[failed[:1]] = 0.5  # the first failed trial is not piled at the edge
    text = _edge_text({"failed": int(mask.sum()), "failed mask": mask, "edge": edge,
                       "failed at the edge": int((mask & (edge >= 0.9)).sum())})
    assert not re.search(r"\b(\d+) of the \1\b", text) and "0 of the" not in text, text


def test_every_labelled_line_of_figs_21_to_23_is_in_a_legend(tmp_path, monkeypatch):
    from somarm.reproduce import throw_maps

    drawn = []
    original = throw_maps.save

    def keep(ctx, fig, name, **kwargs):
        fig.canvas.draw()
        drawn.append((name, [(ax.get_title(), {line.get_label() for line in ax.get_lines()
                                               if not line.get_label().startswith("_")},
                              {text.get_text() for text in ax.get_legend().get_texts()} if ax.get_legend() else set())
                             for ax in fig.axes]))
        return original(ctx, fig, name, **kwargs)

    monkeypatch.setattr(throw_maps, "save", keep)
    assert runner.reproduce(tmp_path, quick=True, only=["throw_maps"], progress=False) == 0
    assert [name for name, _ in drawn][:1] == ["fig21_throw_maps_na25.png"]
    for name, axes in drawn:
        for title, labelled, legend in axes:
            assert labelled <= legend, (name, title, labelled - legend)


@pytest.mark.parametrize("title", ["Fig. 21: throw_distance, action neighbourhood N_A = 25", "reach2 → goals [0, 1]",
                                   None])
def test_a_figures_alt_text_says_what_it_shows_not_its_file_name(tmp_path, title):
    from somarm import plots
    from somarm.reproduce.report import Section, render

    plt = plots.pyplot()
    fig = plt.figure(figsize=(1, 1))
    path = tmp_path / "figures" / "fig21_throw_maps_na25.png"
    path.parent.mkdir()
    fig.savefig(path, metadata={"Title": title} if title else {})
    plt.close(fig)
    section = Section("throw_maps", "Figs. 21-23: varied target distance", [path], [])
    (alt,) = re.findall(r"!\[([^\]]*)\]\(figures/fig21_throw_maps_na25\.png\)", render([section], header=[], out_dir=tmp_path))
    assert alt != "fig21_throw_maps_na25" and "\n" not in alt
    if title:
        assert alt == title.replace("[", "(").replace("]", ")")
    else:
        assert alt.startswith("Figs. 21-23: varied target distance")
