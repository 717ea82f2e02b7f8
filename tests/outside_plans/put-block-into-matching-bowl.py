# Goal: "Put the blocks in the bowls with matching colors."
bowls = [n for n in objects if ' bowl ' in n]
for block in [n for n in objects if ' block ' in n]:
    match = [b for b in bowls if get_color(b) == get_color(block)]
    if match:
        put_first_on_second(block, match[0])
