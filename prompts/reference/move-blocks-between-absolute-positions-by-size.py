# Goal: "Move all the {bigger|smaller} blocks in the {area1} area to the {area2} area."
# As the plain area move, but only blocks of the named size; the others stay put.
X_RANGE = {'top': (0.25, 0.5), 'bottom': (0.5, 0.75)}
Y_RANGE = {'left': (-0.5, 0.0), 'right': (0.0, 0.5)}


def area_bounds(area):
    # (xmin, ymin, xmax, ymax) of an area name such as "bottom right"
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
           if ' block ' in name and f' {size} ' in name and inside(get_obj_pos(name), source)]
for block in to_move:
    put_first_on_second(block, get_random_free_pos(area=target))
