# Goal: "Stack blocks with alternate colors on the {c1} zone, starting with the {c2} color."
words = goal.replace(',', '').replace('.', '').split()
zone_color = words[words.index('zone') - 1]
first_color = words[words.index('color') - 1]
zone = [n for n in objects if ' zone ' in n and get_color(n) == zone_color][0]
blocks = [n for n in objects if ' block ' in n]
firsts = [b for b in blocks if get_color(b) == first_color]
seconds = [b for b in blocks if get_color(b) != first_color]
order = []
for i in range(len(blocks)):
    group = firsts if i % 2 == 0 else seconds
    if group:
        order.append(group.pop(0))
stack_objects_in_order(order, zone)
