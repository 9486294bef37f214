"""Evaluation: train a reference detector on synthgen datasets and score it on real photos."""
