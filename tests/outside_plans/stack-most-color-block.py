# Goal: "Stack blocks of the same color that has the largest quantity in the zone."
zone = [n for n in objects if ' zone ' in n][0]
blocks = [n for n in objects if ' block ' in n]
counts = {}
for b in blocks:
    counts[get_color(b)] = counts.get(get_color(b), 0) + 1
best = max(counts, key=lambda c: counts[c])
chosen = [b for b in blocks if get_color(b) == best]
others = [n for n in is_target_occupied(zone) if ' block ' in n and n not in chosen]
for name in sorted(others, key=lambda n: get_obj_pos(n)[2], reverse=True):
    put_first_on_second(name, get_random_free_pos(targ=zone))
for block in chosen:
    put_first_on_second(block, zone)
