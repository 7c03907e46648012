"""Stateless randomness: every random choice is a hash of (seed, frame, x, y, ...).

The functions use plain integer arithmetic masked to 32 bits, so the same code
gives the same bits on Python ints, on numpy int64 arrays and inside numba
kernels (which compile these very functions). Nothing here imports numba.
"""

from __future__ import annotations

MASK32 = 0xFFFFFFFF
#: Rolls are 24-bit numbers; a chance p happens when ``roll < round(p * ROLL_ONE)``.
ROLL_BITS = 24
ROLL_ONE = 1 << ROLL_BITS

# Salts that keep independent uses of the hash apart.
SALT_MOVE = 0x1B873593
SALT_REACT = 0x68E31DA4
SALT_SPAWN = 0x2545F491
SALT_EMIT = 0x3C6EF372
SALT_PAINT = 0x5851F42D
SALT_SPRAY = 0x0A5F1E3B
SALT_BLAST = 0x4F1BBCDD
SALT_TIMELINE = 0x7C2E9A53
SALT_LAUNCH = 0x2F6A4C1D
SALT_RUN = 0x5BD1E995  # where each column's runs of sinking cells begin (engine.cells._run_end)
SALT_NEIGHBOURS = 0x6A09E667  # neighbour-count rules' rolls (sandmod.passes.counts)


def mix32(h):
    """Scramble a 32-bit value (the 'lowbias32' finaliser by Chris Wellons)."""
    h = h & MASK32
    h ^= h >> 16
    h = (h * 0x7FEB352D) & MASK32
    h ^= h >> 15
    h = (h * 0x846CA68B) & MASK32
    h ^= h >> 16
    return h


def frame_key(seed, frame, salt):
    """A key shared by every cell of one frame, for one use (salt)."""
    return mix32(mix32(mix32(seed ^ 0x9E3779B9) ^ (frame & MASK32)) ^ salt)


def cell_hash(key, x, y):
    """A 32-bit hash of a cell under a frame key; x and y must be below 65536."""
    return mix32(key ^ ((y << 16) | x))


def chance_threshold(p: float) -> int:
    """The roll threshold for probability ``p`` (0 <= p <= 1)."""
    return int(round(min(max(p, 0.0), 1.0) * ROLL_ONE))


def spawn_state(h, life_frames, life_jitter):
    """The shade and lifetime timer of a cell created with hash ``h``."""
    return h & 0xFF, life_frames + ((h >> 8) % (life_jitter + 1))
