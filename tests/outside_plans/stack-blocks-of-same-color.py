# Goal: "Stack all the blocks of the same color together in the same colored zone."
# For every zone: first move blocks of other colours out of it, then stack its colour's blocks there.
zones = [n for n in objects if ' zone ' in n]
blocks = [n for n in objects if ' block ' in n]
for zone in zones:
    intruders = [n for n in is_target_occupied(zone) if ' block ' in n and get_color(n) != get_color(zone)]
    for name in sorted(intruders, key=lambda n: get_obj_pos(n)[2], reverse=True):
        put_first_on_second(name, get_random_free_pos(targ=zones))
for zone in zones:
    for block in [b for b in blocks if get_color(b) == get_color(zone)]:
        put_first_on_second(block, zone)
