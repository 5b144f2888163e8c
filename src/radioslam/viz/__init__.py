"""Figures (matplotlib, Agg backend). Nothing in the numerical core imports this package."""
