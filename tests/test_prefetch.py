"""The kernel's prefetch hint compiles for every array it is given and changes nothing."""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit
from numba.core.errors import TypingError

from sandmod.engine.prefetch import prefetch


@njit
def _prefetched_sum(array):
    """Every cell asked for, then summed: what a loop with prefetches reads is still the array."""
    total = 0
    for y in range(array.shape[0]):
        for x in range(array.shape[1]):
            prefetch(array, y, x)
            total += array[y, x]
    return total


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.int16, np.int32])
@pytest.mark.parametrize("strided", [False, True])
def test_prefetching_the_worlds_array_types_leaves_them_as_they_were(dtype, strided):
    rng = np.random.default_rng(7)
    array = rng.integers(0, 100, (9, 40)).astype(dtype)
    if strided:
        array = array[::2, 1::3]  # not contiguous: the hint takes the address from the strides
    before = array.copy()
    assert _prefetched_sum(array) == int(before.sum())
    assert np.array_equal(array, before)


def test_only_a_two_dimensional_array_can_be_prefetched():
    @njit
    def flat(array):
        prefetch(array, 0, 0)

    with pytest.raises(TypingError):
        flat(np.zeros(4, np.uint8))
