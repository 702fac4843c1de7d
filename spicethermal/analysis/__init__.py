"""Model against measurement: the comparison, the diagnosis, the paper's tables, predictions,
the demo job."""
