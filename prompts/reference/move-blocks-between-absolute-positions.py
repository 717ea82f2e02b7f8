# Goal: "Move all the blocks in the {area1} area to the {area2} area."
# Areas are quadrants named like the front-camera image: top = x in [0.25, 0.5],
# bottom = x in [0.5, 0.75], left = y < 0, right = y > 0.  Each block found in the first area goes
# to a free spot of the second one (free spots keep clear of every object, so nothing else moves).
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
source_area = text.split(' in the ')[1].split(' area')[0]
target_area = text.split(' to the ')[1].split(' area')[0]
source, target = area_bounds(source_area), area_bounds(target_area)
to_move = [name for name in objects if ' block ' in name and inside(get_obj_pos(name), source)]
for block in to_move:
    put_first_on_second(block, get_random_free_pos(area=target))
