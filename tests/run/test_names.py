import pytest

from somarm.run.names import folder_part, run_folder


@pytest.mark.parametrize(("name", "expected"), [
    ("reach2", "reach2"),
    ("gym:Pendulum-v1", "gym-Pendulum-v1"),
    ("dmc:point_mass-easy", "dmc-point_mass-easy"),
    ("gym:ALE/Pong-v5", "gym-ALE-Pong-v5"),
    ("somq+", "somq+"),
    ('gym:a\\b*c?"<>| d', "gym-a-b-c------d"),
])
def test_a_folder_part_keeps_only_what_every_system_takes(name, expected):
    assert folder_part(name) == expected


def test_a_run_folder_is_task_learner_and_seed():
    assert run_folder("dmc:cartpole-balance", "somq", 3) == "dmc-cartpole-balance__somq__seed3"
    assert run_folder("reach2", "somq", 0) == "reach2__somq__seed0"
