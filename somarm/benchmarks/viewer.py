"""``somarm bench viewer``: what live viewing costs a training run (see ``somarm.viewer.bench``)."""

from __future__ import annotations


def main(argv: list[str] | None = None) -> int:
    """Run the viewer overhead benchmark; returns its exit code."""
    from somarm.viewer import bench

    return bench.main(argv)
