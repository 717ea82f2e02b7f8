"""Task G: move-blocks-between-absolute-positions-by-size."""

from __future__ import annotations

from capmj_tasks.move_blocks_between_absolute_positions import AreaMoveTask


class MoveBlocksBetweenAbsolutePositionsBySize(AreaMoveTask):
    """Move the blocks of one size from one quadrant area to another.

    Task Description:
        "Move all the {bigger|smaller} blocks in the {area1} area to the {area2} area."  Quadrant
        areas as in task F.  3–4 blocks start in area1 with both sizes present, 1–3 more in the
        two other quadrants (any size), none in area2.

    Randomizations:
        The ordered pair of distinct quadrants, the size word, how many blocks of area1 have that
        size (1 … n − 1), sizes of the other blocks, colours (distinct), spawn order, all poses
        and yaws (centres ≥ 0.02 m from area borders).

    Success Conditions:
        The blocks of the named size that started in area1 end with their centres in area2;
        every other block (area1 blocks of the other size and blocks elsewhere) ends within
        0.03 m (3-D) of its start.  Progress = blocks meeting their condition / blocks.
    """

    name = "move-blocks-between-absolute-positions-by-size"
    by_size = True


TASK = MoveBlocksBetweenAbsolutePositionsBySize()
