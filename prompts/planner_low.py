import numpy as np, math, itertools
from shapely.geometry import Point, Polygon, LineString, box
from robot_api import get_object_names, get_object, get_objects, get_object_pose, get_camera_images, get_ee_pose, get_joint_positions, solve_ik, move_to_pose, move_through, move_linear, move_until_contact, move_to_joints, home, suction_on, suction_off, is_holding, say

# A UR5e robot with a suction cup on a table. You drive it through a low-level robot API (there is no pick-and-place call). Write the plan for the goal in the last comment.
# Units: metres, radians, quaternions (x, y, z, w). Names look like 'movable small blue block with obj_id 3', 'fixed red zone with obj_id 1'; an int obj_id works too.
# Objects:
# get_object_names() -> names of all objects; the list `objects` holds them too.
# get_object(name) -> dict: 'name', 'obj_id', 'kind' ('block', 'zone', 'bowl', 'ball', 'fixture'), 'color', 'size' ('tiny', 'small', 'big' for blocks), 'fixed' (cannot be picked),
#   'position' [x, y, z] of its centre (a fixture: the centre of its slot (0, 0, 0)), 'quaternion', 'yaw' (rad about z), 'half_size' [hx, hy, hz] in its own frame, 'bbox' (xmin, ymin, zmin, xmax, ymax, zmax) world axis-aligned.
# get_objects() -> get_object(...) of every object. get_object_pose(name) -> ([x, y, z], [qx, qy, qz, qw]).
# get_camera_images() -> {'front' | 'left' | 'right': {'rgb': HxWx3 uint8, 'depth': HxW metres, 'intrinsics': 3x3, 'extrinsics': 4x4 camera-to-world (x right, y down, z forward)}}.
# Robot (the suction tool always points straight down: a tool pose is the tip position [x, y, z] and a yaw):
# get_ee_pose() -> ([x, y, z], yaw) of the suction tip. get_joint_positions() -> 6 joint angles. solve_ik(position, yaw=None) -> 6 joint angles.
# move_to_pose(position, yaw=None): planned move of the tip to the pose (up above everything on the table, across, straight down); yaw None keeps the tool's yaw.
# move_through(waypoints, yaw=None): straight lines (never planned around anything) through [x, y, z] or ([x, y, z], yaw) waypoints. move_linear(position, yaw=None, speed=None): one straight line (speed m/s, at most 1.5).
# move_until_contact(position, yaw=None, speed=None) -> True when it stopped because the tool (the cup, or the object it holds) touched something, False when it reached position; position may be up to 0.05 below the table.
# move_to_joints(joints): joint-space move, planned around obstacles. home(): the same to the arm folded over its base, out of the cameras' view.
# suction_on() -> True when it grips: it grips only the movable object the cup touches at that moment. suction_off(): let go. is_holding() -> whether it holds an object.
# say(message) logs a message.
# Errors: UnreachablePose (nothing moved: out of reach, or below the table top, z < 0, except for move_until_contact), MotionPlanningError (nothing moved: no clear path for move_to_pose, move_to_joints, home), CollisionDetected (the arm, cup or held object touched something on the way; the arm stops there).
# A pick: move above the object's top, move_until_contact down onto it, suction_on. A place: move above the spot high enough for what hangs below the tip, move_until_contact down, suction_off.
# The cup grips where it touches: the held object's centre stays where it was relative to the tip, and turning the tool's yaw turns the held object with it.
# Table: x from 0.25 (top/rear) to 0.75 (bottom/front), y from -0.5 (left) to 0.5 (right), z up, table top z = 0, robot base at (0, 0).
# Halves: top x < 0.5, bottom x > 0.5, left y < 0, right y > 0. Blocks: tiny 0.02 m, small 0.04 m, big 0.06 m cubes. Zones: flat squares, 0.12 m unless scaled up. Bowls: 0.12 m wide.
# Warm colours: red, yellow, orange, brown, pink, gold. Cool colours: blue, green, cyan, purple, gray, violet, indigo, silver.
# Fixed objects (zones, bowls, balls, fixtures) cannot be picked; neither can an object with something on top of it. Blocks look the same after a quarter turn.
# Rules: no imports and no classes; only the functions above, np, math, itertools and shapely. Write the whole plan at once, with comments on your reasoning.

#@ stop: ["\n\nobjects = ["]

#@ example: stack_in_zone
#@ scene: {"objects": [["zone", "green", 0.45, 0.25], ["zone", "red", 0.62, -0.3], ["block", "blue", 0.4, -0.15], ["block", "yellow", 0.6, 0.05], ["block", "red", 0.33, 0.05]]}
#@ task: stack-all-blocks-on-a-zone
#@ info: {"zone": 1, "distractor_zones": [2], "blocks": [3, 4, 5]}
objects = ['fixed green zone with obj_id 1', 'fixed red zone with obj_id 2', 'movable small blue block with obj_id 3', 'movable small yellow block with obj_id 4', 'movable small red block with obj_id 5']
# Stack all blocks in the green zone.
# Each block: pick it from above with a guarded descent, carry it over the zone centre, lower it until it touches what is there (the zone or the stack), let go.
zone = get_object('fixed green zone with obj_id 1')
zx, zy, _ = zone['position']
for name in [n for n in objects if ' block ' in n]:
    block = get_object(name)
    x, y, _ = block['position']
    top = block['bbox'][5]
    move_to_pose([x, y, top + 0.03])
    move_until_contact([x, y, top - 0.02])
    if not suction_on():
        raise RuntimeError(f'the suction did not grip {name}')
    hang = get_ee_pose()[0][2] - get_object(name)['bbox'][2]  # from the tip down to the block's bottom
    stack_top = max(o['bbox'][5] for o in get_objects() if o['name'] != name and abs(o['position'][0] - zx) < 0.06 and abs(o['position'][1] - zy) < 0.06)
    move_to_pose([zx, zy, stack_top + hang + 0.03])
    move_until_contact([zx, zy, hang - 0.04])
    suction_off()
#@ end

#@ example: on_block_lined_up_and_bowl
#@ scene: {"objects": [["block", "blue", 0.55, -0.2, "small", null, 0.5], ["block", "yellow", 0.4, 0.1, "small", null, 0.2], ["bowl", "red", 0.6, 0.25]]}
#@ check: np.hypot(get_object(2)['position'][0] - get_object(1)['position'][0], get_object(2)['position'][1] - get_object(1)['position'][1]) < 0.01 and get_object(2)['position'][2] > 0.05
#@ check: abs((get_object(2)['yaw'] - get_object(1)['yaw'] + math.pi / 4) % (math.pi / 2) - math.pi / 4) < 0.05
objects = ['movable small blue block with obj_id 1', 'movable small yellow block with obj_id 2', 'fixed red bowl with obj_id 3']
# Put the yellow block on the blue block, lined up with it.
# Helpers: pick from above; place the held block centred over (x, y), turned to a yaw, lowered until it touches.
def pick(name):
    o = get_object(name)
    x, y, _ = o['position']
    move_to_pose([x, y, o['bbox'][5] + 0.03])
    move_until_contact([x, y, o['bbox'][5] - 0.02])
    if not suction_on():
        raise RuntimeError(f'the suction did not grip {name}')

def place(name, x, y, yaw=None):
    o = get_object(name)
    tip, tool_yaw = get_ee_pose()
    # blocks look the same every quarter turn: turn by at most 45 degrees
    turn = 0.0 if yaw is None else (yaw - o['yaw'] + math.pi / 4) % (math.pi / 2) - math.pi / 4
    # the tip goes where the block's centre must end, less the block's offset from the tip, turned with it
    dx, dy = o['position'][0] - tip[0], o['position'][1] - tip[1]
    tx = x - (math.cos(turn) * dx - math.sin(turn) * dy)
    ty = y - (math.sin(turn) * dx + math.cos(turn) * dy)
    hang = tip[2] - o['bbox'][2]
    below = max([p['bbox'][5] for p in get_objects() if p['name'] != name and p['bbox'][0] - 0.03 < x < p['bbox'][3] + 0.03 and p['bbox'][1] - 0.03 < y < p['bbox'][4] + 0.03] + [0.0])
    move_to_pose([tx, ty, below + hang + 0.03], tool_yaw + turn)
    move_until_contact([tx, ty, hang - 0.04], tool_yaw + turn)
    suction_off()

blue = get_object('movable small blue block with obj_id 1')
pick('movable small yellow block with obj_id 2')
place('movable small yellow block with obj_id 2', blue['position'][0], blue['position'][1], blue['yaw'])
#@ end

#@ example: unstack_and_home
#@ scene: {"objects": [["block", "red", 0.55, 0.1, "small", 0.02], ["block", "green", 0.55, 0.1, "small", 0.06], ["block", "blue", 0.55, 0.1, "small", 0.1]]}
#@ check: all(get_object(i)['position'][0] < 0.5 and get_object(i)['position'][2] < 0.03 for i in (1, 2, 3))
objects = ['movable small red block with obj_id 1', 'movable small green block with obj_id 2', 'movable small blue block with obj_id 3']
# Take the tower apart, put every block on the table in the top half, then move the arm home.
# Top half: x < 0.5. Highest block first; spots 0.1 m apart along y at x = 0.35.
blocks = sorted([n for n in objects if ' block ' in n], key=lambda n: get_object(n)['position'][2], reverse=True)
for i, name in enumerate(blocks):
    o = get_object(name)
    x, y, _ = o['position']
    move_to_pose([x, y, o['bbox'][5] + 0.03])
    move_until_contact([x, y, o['bbox'][5] - 0.02])
    if not suction_on():
        raise RuntimeError(f'the suction did not grip {name}')
    hang = get_ee_pose()[0][2] - get_object(name)['bbox'][2]
    spot = [0.35, -0.1 + 0.1 * i]
    move_to_pose([spot[0], spot[1], hang + 0.03])
    move_until_contact([spot[0], spot[1], hang - 0.04])
    suction_off()
home()
#@ end

#@ example: into_bowl_through_waypoints
#@ scene: {"objects": [["bowl", "green", 0.5, 0.0], ["block", "red", 0.4, -0.25], ["block", "blue", 0.62, 0.25]]}
#@ check: np.hypot(get_object(2)['position'][0] - 0.5, get_object(2)['position'][1]) < 0.05
#@ check: np.hypot(get_object(3)['position'][0] - 0.62, get_object(3)['position'][1] - 0.25) < 0.01
objects = ['fixed green bowl with obj_id 1', 'movable small red block with obj_id 2', 'movable small blue block with obj_id 3']
# Put the red block into the green bowl, carrying it high over the bowl's rim.
red = get_object('movable small red block with obj_id 2')
bowl = get_object('fixed green bowl with obj_id 1')
x, y, _ = red['position']
move_to_pose([x, y, red['bbox'][5] + 0.03])
move_until_contact([x, y, red['bbox'][5] - 0.02])
if not suction_on():
    raise RuntimeError('the suction did not grip the red block')
tip, _ = get_ee_pose()
bx, by, _ = bowl['position']
high = bowl['bbox'][5] + (tip[2] - get_object(2)['bbox'][2]) + 0.05  # the block's bottom 5 cm over the rim
move_through([[x, y, high], [bx, by, high]])
move_until_contact([bx, by, 0.0])
suction_off()
move_linear([bx, by, high])
#@ end

<<QUESTION>>
