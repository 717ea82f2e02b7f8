import numpy as np, math
from env_utils import get_obj_names, get_obj_pos, get_bbox, get_color, is_target_occupied, bbox_contains_pt, is_obj_visible
from plan_utils import parse_obj_name

# Set ret_val to the answer to the question in the last comment: True or False for a yes/no question, a number for "how many", a list of names for "which" or "what are".
# Names look like 'movable small blue block with obj_id 3' (blocks: tiny 0.02 m, small 0.04 m, big 0.06 m cubes) and 'fixed red zone with obj_id 1'.
# get_obj_pos(name) -> [x, y, z] of the centre (metres). get_color(name) -> 'blue'. get_bbox(name) -> (xmin, ymin, zmin, xmax, ymax, zmax).
# bbox_contains_pt(container, obj) -> whether obj's centre lies inside container's footprint seen from above (a zone's turned square, a bowl's disc).
# is_obj_visible(name) -> whether the scene has that object. is_target_occupied(name) -> names of the objects overlapping that object.
# parse_obj_name(description, f'objects = {get_obj_names()}') -> the names matching a description (another program answers it).
# Table: x from 0.25 (top/rear) to 0.75 (bottom/front), y from -0.5 (left) to 0.5 (right), z up. left = smaller y, right = larger y, front = larger x, rear = smaller x.
# Rules: no imports; only these functions, np and math. Use the exact names from objects.

#@ stop: ["\n\nobjects = ["]

#@ example: right_of_bowl
#@ scene: {"objects": [["bowl", "yellow", 0.45, -0.2], ["block", "blue", 0.55, 0.15], ["block", "yellow", 0.4, 0.3]]}
#@ expect: true
objects = ['fixed yellow bowl with obj_id 1', 'movable small blue block with obj_id 2', 'movable small yellow block with obj_id 3']
# is the blue block to the right of the yellow bowl?
# right = larger y.
ret_val = get_obj_pos('movable small blue block with obj_id 2')[1] > get_obj_pos('fixed yellow bowl with obj_id 1')[1]
#@ end

#@ example: count_colour
#@ scene: {"objects": [["bowl", "yellow", 0.45, -0.2], ["block", "blue", 0.55, 0.15], ["block", "yellow", 0.4, 0.3]]}
#@ expect: 2
objects = ['fixed yellow bowl with obj_id 1', 'movable small blue block with obj_id 2', 'movable small yellow block with obj_id 3']
# how many yellow objects are there?
ret_val = len([name for name in objects if get_color(name) == 'yellow'])
#@ end

#@ example: block_in_zone
#@ scene: {"objects": [["zone", "blue", 0.5, 0.2], ["block", "green", 0.53, 0.23], ["block", "red", 0.4, -0.2]]}
#@ expect: true
objects = ['fixed blue zone with obj_id 1', 'movable small green block with obj_id 2', 'movable small red block with obj_id 3']
# is the green block in the blue zone?
# In a zone means: the centre inside its turned square.
ret_val = bbox_contains_pt('fixed blue zone with obj_id 1', 'movable small green block with obj_id 2')
#@ end

<<QUESTION>>
