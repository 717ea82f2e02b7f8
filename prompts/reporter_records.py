# A robot arm picked and placed objects on a table. capmj has measured the scene after the robot
# acted, with the rules the task uses. `objects` holds one dict per object:
#   "name"        the object's full name
#   "kind"        "block", "zone", "bowl", "ball" or "fixture"
#   "color"       its colour;  "size": "tiny", "small" or "big" for blocks, else None
#   "area"        the quarter of the table its centre is in: "top left", "top right", "bottom left", "bottom right"
#   "start_area"  the quarter it was in before the robot acted
#   "rests_on"    "table", or the full name of the block (or bowl) it is centred on, or "nothing"
#   "below"       the full names of the blocks it rests on (several when it bridges them, as in a pyramid)
#   "level"       1 when it rests on the table, a zone or in a bowl; 2 on blocks of level 1; 3 on level 2 ...
#   "inside"      the full name of the zone or bowl it is in, "" when none;  "inside_color": its colour, or ""
#   "holds"       for zones and bowls: the full names of the movable objects inside it
#   "tilted"      True when it leans or lies on a side
#   "centre"      [x, y, z] in metres
# Everything is measured already: do not compute distances, compare the records with the goal.
# Write Python code that sets three names:
#   judge = True when every part of the goal holds, else False
#   reason = a short sentence saying which part of the goal does not hold
#   wrong = the full names of the movable objects that break the goal ([] when judge is True)
# Use only `objects` and Python built-ins; never import anything.

#@ stop: ["\n\n# example goal", "\n\nobjects = [", "\n    {'name': "]

# example goal: Put all the red blocks in the green zone.
red_blocks = [o for o in objects if o["kind"] == "block" and o["color"] == "red"]
green_zone = [o for o in objects if o["kind"] == "zone" and o["color"] == "green"][0]
wrong = [b["name"] for b in red_blocks if b["inside"] != green_zone["name"]]
judge = len(wrong) == 0
reason = "red blocks outside the green zone: " + ", ".join(wrong)

# example goal: Stack the blue blocks into one tower in the yellow zone.
blue_blocks = [o for o in objects if o["kind"] == "block" and o["color"] == "blue"]
yellow_zone = [o for o in objects if o["kind"] == "zone" and o["color"] == "yellow"][0]
wrong = [b["name"] for b in blue_blocks if b["inside"] != yellow_zone["name"] or b["tilted"]]
levels = sorted(b["level"] for b in blue_blocks)
judge = len(wrong) == 0 and levels == list(range(1, len(blue_blocks) + 1))
reason = "blue block levels " + str(levels) + ", outside the zone or tilted: " + ", ".join(wrong)

# example goal: Move the blocks in the top left area to the bottom left area.
moved = [o for o in objects if o["kind"] == "block" and o["start_area"] == "top left"]
wrong = [b["name"] for b in moved if b["area"] != "bottom left"]
judge = len(wrong) == 0
reason = "blocks not in the bottom left area: " + ", ".join(wrong)

<<QUESTION>>
