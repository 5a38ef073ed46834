"""A run's figures say what their colours mean."""

import numpy as np
import pytest

from somarm import plots, run
from somarm.run import RunConfig


@pytest.mark.parametrize("kind, shade", [("somq", "greedy action unit"), ("motoric", "input unit")])
def test_the_input_map_has_a_colour_bar_that_matches_its_units(tmp_path, monkeypatch, kind, shade):
    result = run.train(RunConfig(task="reach2", learner=kind, n_trials=1, n_steps=300, block=100, seed=2),
                       progress=False)
    figures = {}
    monkeypatch.setattr(plots, "save", lambda fig, path, **kw: figures.setdefault(path.name, fig))
    try:
        plots.run_figures(result, tmp_path)
        fig = figures["input_map.png"]
        bars = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"]
        assert len(bars) == 1, [ax.get_label() for ax in fig.axes]
        assert shade in bars[0].get_ylabel()
        # Each unit's shade is the bar's colour at its unit index.
        learner = result.learner
        if learner.has_action_map:
            indices = np.asarray(learner.q)[0].argmax(axis=1)
        else:
            indices = np.arange(np.asarray(learner.input_weights).shape[1])
        points = fig.axes[0].collections[0]
        bar = bars[0]._colorbar
        np.testing.assert_allclose(points.get_facecolors(), bar.mappable.to_rgba(indices), atol=1e-6)
    finally:
        plots.plt.close("all")


@pytest.mark.parametrize("titled", ["suptitle", "axes", "none"])
def test_a_saved_png_carries_the_figures_title(tmp_path, titled):
    from PIL import Image

    fig, ax = plots.plt.subplots()
    ax.plot([0, 1], [1, 0])
    if titled == "suptitle":
        fig.suptitle("the whole figure")
        ax.set_title("one panel")
    elif titled == "axes":
        ax.set_title("one panel")
    path = plots.save(fig, tmp_path / "f.png")
    said = Image.open(path).text.get("Title")
    assert said == {"suptitle": "the whole figure", "axes": "one panel", "none": None}[titled]
