"""The comparison figure says how many seeds each curve is a median over."""

from somarm.peers import plot


def _result(counts):
    learners = {kind: {"samples": [10, 20], "return": [[-5.0] * n, [-4.0] * n], "wall_seconds": [[1.0] * n, [2.0] * n]}
                for kind, n in counts.items()}
    return {"task": "gym:Reacher-v5", "metric": "return", "episodes": 5, "random_action_return": -43.0,
            "seeds": list(range(max(counts.values()))), "learners": learners}


def _drawn(monkeypatch, result):
    seen = {}
    monkeypatch.setattr(plot, "save", lambda fig, path: seen.setdefault("fig", fig))
    plot.compare_figure(result, "unused.png")
    fig = seen["fig"]
    labels = [text.get_text() for text in fig.axes[0].get_legend().get_texts()]
    return fig._suptitle.get_text(), labels


def test_learners_on_different_seed_sets_are_labelled_with_their_own_counts(monkeypatch):
    title, labels = _drawn(monkeypatch, _result({"somq": 10, "td3": 5}))
    assert "each learner's seeds" in title
    assert any(label.endswith("(10 seeds)") for label in labels) and any(label.endswith("(5 seeds)") for label in labels)


def test_learners_on_one_seed_set_name_it_once_in_the_title(monkeypatch):
    title, labels = _drawn(monkeypatch, _result({"somq": 5, "td3": 5}))
    assert "median over 5 seeds" in title and not any("seeds)" in label for label in labels)


def test_a_curve_of_one_seed_says_seed_not_seeds(monkeypatch):
    _, labels = _drawn(monkeypatch, _result({"somq": 5, "td3": 1}))
    assert any(label.endswith("(1 seed)") for label in labels) and not any("(1 seeds)" in label for label in labels)
