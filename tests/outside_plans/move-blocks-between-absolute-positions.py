# Goal: "Move all the blocks in the {area1} area to the {area2} area."
# Quadrants: top x < 0.5, bottom x > 0.5, left y < 0, right y > 0.
def area_bounds(words):
    xmin, xmax, ymin, ymax = 0.25, 0.75, -0.5, 0.5
    if 'top' in words: xmax = 0.5
    if 'bottom' in words: xmin = 0.5
    if 'left' in words: ymax = 0.0
    if 'right' in words: ymin = 0.0
    return (xmin, ymin, xmax, ymax)

first, second = goal.split(' in the ')[1].split(' area to the ')
src = area_bounds(first.split())
dst = area_bounds(second.replace(' area.', '').split())
blocks = [n for n in objects if ' block ' in n]
moving = [b for b in blocks if src[0] <= get_obj_pos(b)[0] <= src[2] and src[1] <= get_obj_pos(b)[1] <= src[3]]
for block in moving:
    put_first_on_second(block, get_random_free_pos(area=dst))
