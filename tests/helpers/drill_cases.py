"""Drill bits through the built-in capsule arm that the drill tests share."""

#: bits through the built-in capsule arm (radius 0.25 around the x axis from x = -0.25 to 3.25): a hole
#: through it, a blind one, one along its axis from its end, one grazing its side, one oblique, one from
#: its pole along its surface, one grazing it lengthwise
CASES = {
    "through": ([1.0, 0.0, -1.0], [1.0, 0.0, 1.0], 0.1),
    "blind": ([1.0, 0.0, -1.0], [1.0, 0.0, 0.05], 0.1),
    "along the axis": ([-1.0, 0.0, 0.0], [0.5, 0.0, 0.0], 0.1),
    "grazing": ([1.0, 0.22, -1.0], [1.0, 0.22, 1.0], 0.1),
    "oblique": ([0.6, -0.5, -0.6], [1.4, 0.5, 0.7], 0.07),
    # the bit's start on the capsule's pole, travelling along its surface: the fill on the bit's round
    # start reaches that end's pole (found by test_session_drill's random bits; the fill did not converge)
    "from the pole": ([-0.25, 0.0, 0.0], [-0.25, 0.0, 0.5], 0.0625),
    # the axis on the surface along the capsule: a fill longer along the bit than across it
    "grazing lengthwise": ([0.8, 0.25, 0.0], [2.2, 0.25, 0.0], 0.1),
}
