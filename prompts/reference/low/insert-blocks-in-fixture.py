# Goal: "Each L-shaped fixture can hold three blocks ... in fixture's local coordinate system, the
# three places are [(0,0,0),(a,0,0),(0,a,0)]. Fill in all the fixtures ... three different colours."
# The fixture's pose is its local frame.  Blocks sorted by colour and dealt round robin give every
# fixture three colours; slot (0,0,0) of every fixture first, then (a,0,0), then (0,a,0), each
# block lowered at its slot, turned like the fixture.
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
def insert(name, x, y, yaw, away):
    # the held block lowered into a slot centred at (x, y): its bottom must reach the table.  Stopped
    # on a wall or on a neighbour's top, lift it clear and try again 3 mm further `away` (a unit
    # vector pointing out of the L, away from the walls and the filled slots), at most three times.
    o = obj(name)
    tip, tool_yaw = get_ee_pose()
    turn = quarter(yaw - o['yaw'])
    dx, dy = o['position'][0] - tip[0], o['position'][1] - tip[1]
    c, s = math.cos(turn), math.sin(turn)
    tx, ty = x - (c * dx - s * dy), y - (s * dx + c * dy)
    hang = tip[2] - o['bbox'][2]
    above = surface_under(x, y, o, name) + hang + 0.03
    move_to_pose([tx, ty, above], tool_yaw + turn)
    for k in range(4):
        px, py = tx + 0.003 * k * away[0], ty + 0.003 * k * away[1]
        if k:
            move_linear([px, py, above])
        move_until_contact([px, py, hang - 0.04], tool_yaw + turn)
        if get_ee_pose()[0][2] - hang < 0.02:  # the block's bottom is (nearly) down on the table
            break
        move_linear([px, py, above])
    bottom = get_ee_pose()[0][2] - hang
    suction_off()
    placed[name] = (x, y, o['half_size'][0], bottom + 2 * o['half_size'][2])


fixtures = [name for name in objects if ' fixture ' in name]
blocks = sorted([name for name in objects if ' block ' in name], key=lambda b: obj(b)['color'])
a = 2 * obj(blocks[0])['half_size'][2]
seats = [(0.0, 0.0), (a, 0.0), (0.0, a)]
n = len(fixtures)
for slot in range(3):
    for f, fixture in enumerate(fixtures):
        fx = obj(fixture)
        x, y, _ = fx['position']
        c, s = math.cos(fx['yaw']), math.sin(fx['yaw'])
        u, v = seats[slot]
        # 2 mm off the slot centre, away from the walls (-x, -y in the fixture frame) and the block
        # filled before it (slot (a, 0): at -x; slot (0, a): at -y): the walls leave only a few mm
        bu, bv = [(0.002, 0.002), (0.003, 0.002), (0.002, 0.003)][slot]
        au, av = [(0.7071, 0.7071), (1.0, 0.0), (0.0, 1.0)][slot]
        pick(blocks[slot * n + f])
        insert(blocks[slot * n + f], x + c * (u + bu) - s * (v + bv), y + s * (u + bu) + c * (v + bv), fx['yaw'],
               (c * au - s * av, s * au + c * av))
