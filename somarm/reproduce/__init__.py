"""Reproduction of every experiment of Smith (2002): figures and a report that checks each claim."""
