"""Shared by every stage: errors, the time symbol and coordinate helpers, lazy sequences, atomic files."""
