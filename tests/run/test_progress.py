"""The progress display: redrawn in place on a terminal, whole lines (no carriage returns) in a log."""

import io

from somarm.run.progress import Progress


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_a_log_gets_a_line_per_tenth_and_the_last_line_once():
    log = io.StringIO()
    bar = Progress(1000, label="reach2/somq", stream=log, rate_hz=1e9)
    for step in range(100, 1001, 100):
        bar.update(step, -0.5)
    bar.close(1000, -0.5)
    text = log.getvalue()
    assert "\r" not in text
    lines = text.splitlines()
    assert [line.split("] ")[1].split()[0] for line in lines] == [f"{s}/1000" for s in range(100, 1001, 100)]


def test_a_log_is_short_even_with_many_updates():
    log = io.StringIO()
    bar = Progress(100_000, stream=log, rate_hz=1e9)
    for step in range(1, 100_001, 10):
        bar.update(step, 0.0)
    bar.close(100_000, 0.0)
    assert len(log.getvalue().splitlines()) <= 12  # the first, one per tenth, the last


def test_a_terminal_redraws_in_place_and_ends_the_line_once():
    tty = _Terminal()
    bar = Progress(10, stream=tty, rate_hz=1e9)
    for step in range(1, 11):
        bar.update(step, 0.0)
    bar.close(10, 0.0)
    text = tty.getvalue()
    assert text.count("\r") == 10 and text.endswith("\n") and text.count("\n") == 1


def test_a_message_after_an_open_bar_starts_on_its_own_line():
    from somarm.run.progress import end_line

    tty = _Terminal()
    bar = Progress(10, stream=tty, rate_hz=1e9)
    bar.update(5, 0.0)
    end_line()  # what the viewer does before it warns
    tty.write("warning\n")
    bar.update(10, 0.0)
    bar.close(10, 0.0)
    lines = tty.getvalue().split("\n")
    assert lines[1] == "warning" and lines[0].startswith("\r") and lines[2].startswith("\r")
    assert tty.getvalue().endswith("\n") and not tty.getvalue().endswith("\n\n")


def test_no_mean_is_drawn_before_a_whole_block(capsys):
    import io

    stream = io.StringIO()
    bar = Progress(10, label="x", stream=stream)
    bar.update(1, float("nan"), force=True)
    assert "nan" not in stream.getvalue() and "mean reward, last block    -" in stream.getvalue()


def test_a_reporter_gets_the_first_and_last_step_and_few_between(monkeypatch):
    from somarm.run import progress

    got = []
    progress.report_to(lambda label, step, total: got.append((label, step, total)))
    try:
        bar = Progress(100_000, label="Fig. 7", stream=io.StringIO(), enabled=False)
        for step in range(1, 100_001, 10):
            bar.update(step, 0.0)
        bar.close(100_000, 0.0)
    finally:
        progress.report_to(None)
    assert got[0] == ("Fig. 7", 1, 100_000) and got[-1] == ("Fig. 7", 100_000, 100_000)
    assert len(got) <= 2 + 10  # one a second at most (the loop above takes well under 10 s)


def _last_bar_line(text: str) -> str:
    return [line for line in text.splitlines() if "] " in line][-1]


def test_an_episodic_task_shows_the_mean_return_of_its_last_finished_episodes(capsys):
    import re

    import numpy as np

    from somarm import run
    from somarm.run.loop import RECENT_EPISODES

    result = run.train(run.RunConfig(task="reach2_obstacle", n_trials=4, n_steps=3000, seed=1), progress=True)
    shown = _last_bar_line(capsys.readouterr().err)
    returns = result.episodes.returns  # in the order they ended
    assert len(returns) > RECENT_EPISODES  # enough episodes for the window to matter
    found = re.search(r"mean return, last (\d+) episodes ([-+]\d+\.\d+)", shown)
    assert found and "mean reward" not in shown, shown
    assert int(found.group(1)) == RECENT_EPISODES
    assert float(found.group(2)) == round(float(np.mean(returns[-RECENT_EPISODES:])), 4)


def test_a_one_step_task_shows_the_mean_reward_of_its_last_block_named_so(capsys):
    import re

    from somarm import run

    # named apart from summary.json's final_mean_reward, the mean over a final window of several blocks
    result = run.train(run.RunConfig(task="reach2", n_trials=3, n_steps=1000, seed=1), progress=True)
    shown = _last_bar_line(capsys.readouterr().err)
    found = re.search(r"mean reward, last block ([-+]\d+\.\d+)", shown)
    assert found and "return" not in shown, shown
    assert float(found.group(1)) == round(float(result.block_means[-1].mean()), 4)
