# Goal: "Put the blocks in the bowls with matching colors."
# Each block goes into the bowl of its own colour; a block without such a bowl stays out.
bowls = [name for name in objects if ' bowl ' in name]
blocks = [name for name in objects if ' block ' in name]
for block in blocks:
    matching = [bowl for bowl in bowls if get_color(bowl) == get_color(block)]
    if matching:
        put_first_on_second(block, matching[0])
