"""Reproducible experiments run from the CLI (`lf3pm experiment NAME -o DIR`)."""
