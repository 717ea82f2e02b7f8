# Goal: "Divide the blocks into groups of {k} and stack each group (also including the group with
# block number less than {k}) in a different zone."
# First take every block out of the zones (so no zone holds a stray block), then stack group j in zone j.
k = int(goal.split('groups of ')[1].split()[0])
zones = [n for n in objects if ' zone ' in n]
blocks = [n for n in objects if ' block ' in n]
for zone in zones:
    inside = [n for n in is_target_occupied(zone) if ' block ' in n]
    for name in sorted(inside, key=lambda n: get_obj_pos(n)[2], reverse=True):
        put_first_on_second(name, get_random_free_pos(targ=zones))
groups = [blocks[i:i + k] for i in range(0, len(blocks), k)]
for group, zone in zip(groups, zones):
    stack_objects_in_order(group, zone)
