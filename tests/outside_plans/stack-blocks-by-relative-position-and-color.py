# Goal: "Stack all the blocks, which are to the {left|right|front|rear} of the {color} block with
# {horizontal|front-back} distance larger than 0.05, in the {zone color} zone."
# left/right = y-/y+, front/rear = x+/x-; the selection is made from the initial positions.
words = goal.replace(',', '').replace('.', ' ').split()  # first version kept the full stop: 'zone.' was not found
direction = words[words.index('of') - 1]
ref_color = words[words.index('block') - 1]
zone_color = words[words.index('zone') - 1]
ref = [n for n in objects if ' block ' in n and get_color(n) == ref_color][0]
zone = [n for n in objects if ' zone ' in n and get_color(n) == zone_color][0]
rx, ry, _ = get_obj_pos(ref)
chosen = []
for b in objects:
    if ' block ' not in b or b == ref:
        continue
    x, y, _ = get_obj_pos(b)
    d = {'left': ry - y, 'right': y - ry, 'front': x - rx, 'rear': rx - x}[direction]
    if d > 0.05:
        chosen.append(b)
others = [n for n in is_target_occupied(zone) if ' block ' in n and n not in chosen]
for name in sorted(others, key=lambda n: get_obj_pos(n)[2], reverse=True):
    put_first_on_second(name, get_random_free_pos(targ=zone))
for block in chosen:
    put_first_on_second(block, zone)
