"""Evaluation: bounds, metrics and the paper's experiments (pure computation; figures live in viz)."""
