# Goal: "Stack blocks of the same size in the {c1} zone and {c2} zone respectively."
# "respectively" pairs the sizes with the zones in order: the big blocks go to the first zone,
# the small blocks to the second.
words = goal.rstrip('.').split()
first_color = words[words.index('zone') - 1]
second_color = words[words.index('respectively') - 2]


def zone_of(color):
    return [name for name in objects if f' {color} zone ' in name][0]


big_blocks = [name for name in objects if ' big ' in name and ' block ' in name]
small_blocks = [name for name in objects if ' small ' in name and ' block ' in name]
for block in big_blocks:
    put_first_on_second(block, zone_of(first_color))
for block in small_blocks:
    put_first_on_second(block, zone_of(second_color))
