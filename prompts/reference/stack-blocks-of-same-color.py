# Goal: "Stack all the blocks of the same color together in the same colored zone."
# For every zone, stack the blocks of the zone's colour on it.  Blocks whose colour has no zone
# stay where they are (they never start inside a zone).
zones = [name for name in objects if ' zone ' in name]
blocks = [name for name in objects if ' block ' in name]
for zone in zones:
    color = get_color(zone)
    for block in blocks:
        if get_color(block) == color:
            put_first_on_second(block, zone)
