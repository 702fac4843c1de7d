"""Foster and Cauer ladders, their conversions, errors, progress, synthetic curves (no files, no
figures)."""
