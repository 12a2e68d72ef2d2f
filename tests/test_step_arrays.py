"""The cached index arrays of a fast-forward: the same values as working them out step by step."""

from __future__ import annotations

import numpy as np
import pytest

from emulator.flight.arrays import step_offsets_s, steps_done


@pytest.mark.parametrize("dt_s", [0.02, 0.01, 1.0 / 3.0])
def test_step_offsets_are_each_steps_time(dt_s: float) -> None:
    offsets = step_offsets_s(7, dt_s)
    assert offsets.shape == (7, 1, 1) and not offsets.flags.writeable
    assert offsets[:, 0, 0].tolist() == [i * dt_s for i in range(1, 8)]
    assert step_offsets_s(7, dt_s) is offsets  # kept, not rebuilt


@pytest.mark.parametrize("every", [1, 2, 5])
def test_steps_done_counts_the_periodic_steps_at_or_before_each_step(every: int) -> None:
    for first in range(every):
        for count in (1, 2, every, 3 * every + 1, 50):
            done = steps_done(count, first, every)
            periodic = [i for i in range(count) if i >= first and (i - first) % every == 0]
            expected = [sum(p <= i for p in periodic) for i in range(count)]
            assert done.tolist() == expected
            assert not done.flags.writeable
            with pytest.raises(ValueError):
                done[0] = 0
    assert np.array_equal(steps_done(4, 0, 5), [1, 1, 1, 1])
