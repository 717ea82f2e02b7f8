# Goal: "Stack all blocks in the {color} zone."
# The colour is the word before "zone"; every block goes onto the zone centre, one on top of the
# other (put_first_on_second onto a zone lands on whatever is already stacked there).
words = goal.rstrip('.').split()
zone_color = words[words.index('zone') - 1]
zone = [name for name in objects if f' {zone_color} zone ' in name][0]
blocks = [name for name in objects if ' block ' in name]
for block in blocks:
    put_first_on_second(block, zone)
