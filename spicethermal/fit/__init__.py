"""The ladder fit (order selection, weighting, result object, bootstrap) and the joint fits of a
ladder with an effect, with the effects' fast forward models."""
