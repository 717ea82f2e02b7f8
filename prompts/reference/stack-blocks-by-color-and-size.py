# Goal: "Stack only the {bigger|smaller} blocks of {warm|cool} color in the {color} zone."
# Warm and cool colour names as the benchmark defines them; only blocks of the named size and
# temperature are stacked, the others are left alone.
warm_colors = ['red', 'yellow', 'orange', 'brown', 'pink', 'gold']
cool_colors = ['blue', 'green', 'cyan', 'purple', 'gray', 'violet', 'indigo', 'silver']
words = goal.rstrip('.').split()
size = 'big' if 'bigger' in words else 'small'
palette = warm_colors if 'warm' in words else cool_colors
zone_color = words[words.index('zone') - 1]
zone = [name for name in objects if f' {zone_color} zone ' in name][0]
selected = [name for name in objects
            if ' block ' in name and f' {size} ' in name and get_color(name) in palette]
for block in selected:
    put_first_on_second(block, zone)
