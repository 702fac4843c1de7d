"""Figures (matplotlib, imported only here)."""
