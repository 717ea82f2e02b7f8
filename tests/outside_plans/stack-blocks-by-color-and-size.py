# Goal: "Stack only the {bigger|smaller} blocks of {warm|cool} color in the {color} zone."
warm = ['red', 'yellow', 'orange', 'brown', 'pink', 'gold']
cool = ['blue', 'green', 'cyan', 'purple', 'gray', 'violet', 'indigo', 'silver']
size = 'big' if 'bigger' in goal else 'small'
palette = warm if ' warm ' in goal else cool
zone_color = goal.split(' zone')[0].split()[-1]
zone = [n for n in objects if ' zone ' in n and get_color(n) == zone_color][0]
blocks = [n for n in objects if ' block ' in n]
chosen = [b for b in blocks if f' {size} ' in b and get_color(b) in palette]
# "only": no other block may stay in the zone.
others = [n for n in is_target_occupied(zone) if ' block ' in n and n not in chosen]
for name in sorted(others, key=lambda n: get_obj_pos(n)[2], reverse=True):
    put_first_on_second(name, get_random_free_pos(targ=zone))
for block in chosen:
    put_first_on_second(block, zone)
