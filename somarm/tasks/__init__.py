"""Registered tasks: the reaching arms and the projectile launcher of Smith (2002)."""
