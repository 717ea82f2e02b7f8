# Goal: "Stack blocks with alternate colors on the {c1} zone, starting with the {c2} color."
# Bottom block of colour c2, then the other colour, then c2 again, and so on.
words = goal.replace(',', '').rstrip('.').split()
zone_color = words[words.index('zone') - 1]
first_color = words[words.index('color') - 1]
zone = [name for name in objects if f' {zone_color} zone ' in name][0]
blocks = [name for name in objects if ' block ' in name]
first = [name for name in blocks if get_color(name) == first_color]
second = [name for name in blocks if get_color(name) != first_color]
order = []
for k in range(len(blocks)):
    group = first if k % 2 == 0 else second
    if group:
        order.append(group.pop(0))
stack_objects_in_order(order, zone)
