"""The fluids figures (``tools/dev/fluids.py``): the stripe measure tells a comb from a mixture."""

from __future__ import annotations

import numpy as np

import fluids


def test_a_comb_is_striped_through_and_a_mixture_or_two_layers_not_at_all():
    comb = np.where(np.arange(20)[:, None] % 2 == 0, 1, 2) * np.ones((1, 30), int)
    assert fluids.striped_rows(comb, 1, 2) == 16  # rows 1..18 hold both; all but their first and last
    mixture = np.random.default_rng(1).choice([1, 2], size=(20, 30))
    assert fluids.striped_rows(mixture, 1, 2) == 0
    layers = np.where(np.arange(20)[:, None] < 10, 1, 2) * np.ones((1, 30), int)
    assert fluids.striped_rows(layers, 1, 2) == 0


def test_rows_the_fluids_barely_fill_are_no_stripes():
    sparse = np.zeros((9, 30), int)
    sparse[::2, 0], sparse[1::2, 0] = 1, 2  # one cell a row, alternating: drops in the air, not a comb
    assert fluids.striped_rows(sparse, 1, 2) == 0
