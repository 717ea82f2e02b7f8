# Goal: "Stack blocks of the same color that has the largest quantity in the zone."
# Count the blocks of each colour and stack those of the most frequent colour in the zone.
zone = [name for name in objects if ' zone ' in name][0]
blocks = [name for name in objects if ' block ' in name]
counts = {}
for block in blocks:
    counts[get_color(block)] = counts.get(get_color(block), 0) + 1
top = max(counts, key=lambda colour: counts[colour])
stack_objects_in_order([block for block in blocks if get_color(block) == top], zone)
