# Goal: stack the big blocks in the first named zone and the small ones in the second.
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
words = goal.rstrip('.').split()
first_color = words[words.index('zone') - 1]
second_color = words[words.index('respectively') - 2]


def zone_of(color):
    return [name for name in objects if f' {color} zone ' in name][0]


big_blocks = [name for name in objects if ' big ' in name and ' block ' in name]
small_blocks = [name for name in objects if ' small ' in name and ' block ' in name]
for block in big_blocks:
    put_on(block, zone_of(first_color))
for block in small_blocks:
    put_on(block, zone_of(second_color))
