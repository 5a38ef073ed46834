"""Stable-Baselines3 and Gymnasium around somarm's tasks: adapters, vectorised envs and ``somarm compare``."""
