# Goal: put each block into a bowl of another colour, one block per bowl: the first assignment of
# bowls to blocks with every colour different.
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
bowls = [name for name in objects if ' bowl ' in name]
blocks = [name for name in objects if ' block ' in name]
colour = {name: obj(name)['color'] for name in bowls + blocks}
assignment = None
for chosen in itertools.permutations(bowls, len(blocks)):
    if all(colour[block] != colour[bowl] for block, bowl in zip(blocks, chosen)):
        assignment = list(zip(blocks, chosen))
        break
if assignment is None:
    say('no bowl assignment with mismatching colours exists')
else:
    for block, bowl in assignment:
        put_on(block, bowl)
