# Goal: "Move all the bigger/smaller blocks in the {area} area to the {area} area": each block of the source
# area to a free spot of the target area (halves: top x < 0.5, bottom x > 0.5, left y < 0, right y > 0).
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
X_RANGE = {'top': (0.25, 0.5), 'bottom': (0.5, 0.75)}
Y_RANGE = {'left': (-0.5, 0.0), 'right': (0.0, 0.5)}


def area_bounds(area):
    # (xmin, ymin, xmax, ymax) of an area name such as "top left"
    vertical, horizontal = area.split()
    (xmin, xmax), (ymin, ymax) = X_RANGE[vertical], Y_RANGE[horizontal]
    return (xmin, ymin, xmax, ymax)


def inside(pos, bounds):
    return bounds[0] < pos[0] < bounds[2] and bounds[1] < pos[1] < bounds[3]


text = goal.rstrip('.')
size = 'big' if ' bigger ' in text else 'small'
source_area = text.split(' in the ')[1].split(' area')[0]
target_area = text.split(' to the ')[1].split(' area')[0]
source, target = area_bounds(source_area), area_bounds(target_area)
to_move = [name for name in objects
           if ' block ' in name and f' {size} ' in name and inside(obj(name)['position'], source)]
for block in to_move:
    x, y = free_spot(target)
    put(block, x, y, 0.0)
