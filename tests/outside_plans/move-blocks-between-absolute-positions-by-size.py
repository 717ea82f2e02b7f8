# Goal: "Move all the {bigger|smaller} blocks in the {area1} area to the {area2} area."
def area_bounds(words):
    xmin, xmax, ymin, ymax = 0.25, 0.75, -0.5, 0.5
    if 'top' in words: xmax = 0.5
    if 'bottom' in words: xmin = 0.5
    if 'left' in words: ymax = 0.0
    if 'right' in words: ymin = 0.0
    return (xmin, ymin, xmax, ymax)

size = 'big' if 'bigger' in goal else 'small'
first, second = goal.split(' in the ')[1].split(' area to the ')
src = area_bounds(first.split())
dst = area_bounds(second.replace(' area.', '').split())
for block in [n for n in objects if f' {size} ' in n and ' block ' in n]:
    x, y, _ = get_obj_pos(block)
    if src[0] <= x <= src[2] and src[1] <= y <= src[3]:
        put_first_on_second(block, get_random_free_pos(area=dst))
