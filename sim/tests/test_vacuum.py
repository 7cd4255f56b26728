"""The vacuum tool: suction on with a part's top face at the cup picks it up (its input reads true while it is held),
suction off lets go and the part falls and rests; nothing is picked from too far, off-centre or off-square.
In-process (World + Controller + WorldLoop, no servers): the physics is deterministic and fast."""
from __future__ import annotations

import numpy as np
import pytest

from sim import motion
from sim.cell_file import parse_simulation
from sim.controller import Controller, WorldLoop
from sim.world import World

SUCTION_DO, VACUUM_DI = 4, 5
DOWN = np.array([-2.2214415, -2.2214415, 0.0])  # tool z pointing down (the demo's home orientation)


def vacuum_cell(parts: list, stations: list | None = None):
    spec = parse_simulation({"simulation": {
        "arms": [{"group": "arm", "base": [0, 0, 0, 0],
                  "tool": {"kind": "vacuum", "suction_output": SUCTION_DO, "vacuum_input": VACUUM_DI}}],
        "parts": {"positions": parts}, "stations": stations or []}})
    world = World(seed=0, spec=spec)
    ctl = Controller(world)
    return world, ctl, WorldLoop(world, [ctl], ctl.lock)


def move_to(loop: WorldLoop, ctl: Controller, xyz, rot=DOWN, speed: float = 0.25) -> None:
    ctl.arm.start(motion.LinearMove(ctl.arm.q_set, np.array([*xyz, *rot]), speed, 1.0, ctl.tcp))
    run(loop, 5.0, until=lambda: not ctl.arm.busy() and ctl.arm.settled(*ctl.actual()))
    np.testing.assert_allclose(ctl.snapshot.actual_TCP_pose[:3], xyz, atol=5e-4)


def run(loop: WorldLoop, seconds: float, until=None) -> None:
    for _ in range(int(seconds * 500)):
        loop.tick()
        if until is not None and until():
            return
    if until is not None:
        raise AssertionError("condition not reached")


def suction(ctl: Controller, on: bool) -> None:
    ctl.set_digital_out(SUCTION_DO, on)


def held(ctl: Controller) -> bool:
    return bool(ctl.snapshot.digital_in & (1 << VACUUM_DI))


@pytest.fixture
def cell():
    world, ctl, loop = vacuum_cell([[-0.45, -0.1]])
    run(loop, 0.3)
    yield world, ctl, loop
    world.close()


def test_picks_up_carries_and_releases_a_cube(cell) -> None:
    world, ctl, loop = cell
    cube = world.cubes[0]
    assert ctl.tcp[2] == pytest.approx(0.09)  # TCP at the cup face
    move_to(loop, ctl, (-0.45, -0.1, 0.043))  # cup face 3 mm above the cube's top face
    f_before = np.linalg.norm(ctl.snapshot.ft_raw[:3])
    assert not held(ctl)
    suction(ctl, True)
    run(loop, 0.1)
    assert held(ctl), "vacuum input must read true with the part on the cup"
    assert ctl.snapshot.digital_out & (1 << SUCTION_DO)
    move_to(loop, ctl, (-0.40, 0.05, 0.20), speed=0.2)
    run(loop, 0.3)
    pos, _ = world.p.getBasePositionAndOrientation(cube)
    np.testing.assert_allclose(pos, (-0.40, 0.05, 0.20 - 0.02), atol=2e-3)  # hanging on the cup face
    assert held(ctl)
    # The wrist carries the part now (~0.1 kg).
    assert 0.6 < np.linalg.norm(ctl.snapshot.ft_raw[:3]) - f_before < 1.5
    suction(ctl, False)
    run(loop, 0.02)
    assert not held(ctl)
    run(loop, 1.5)  # falls 16 cm and comes to rest on the table
    pos, orn = world.p.getBasePositionAndOrientation(cube)
    assert pos[2] == pytest.approx(0.02, abs=1e-3)
    assert np.linalg.norm(world.p.getBaseVelocity(cube)[0]) < 1e-2
    assert np.hypot(pos[0] + 0.40, pos[1] - 0.05) < 0.03
    # Suction on again, far above the cube: nothing to pick.
    suction(ctl, True)
    run(loop, 0.2)
    assert not held(ctl)


def test_suction_switched_on_before_reaching_the_part_takes_it_on_arrival(cell) -> None:
    world, ctl, loop = cell
    move_to(loop, ctl, (-0.45, -0.1, 0.06))
    suction(ctl, True)
    run(loop, 0.1)
    assert not held(ctl), "20 mm above the cube: out of the cup's reach"
    ctl.arm.start(motion.LinearMove(ctl.arm.q_set, np.array([-0.45, -0.1, 0.042, *DOWN]), 0.05, 0.5, ctl.tcp))
    run(loop, 3.0, until=lambda: held(ctl))
    assert ctl.snapshot.actual_TCP_pose[2] > 0.042 + 0.001, "taken within reach, before the move ended"


@pytest.mark.parametrize("offset, tilt_deg, picked", [
    ((0.0, 0.0, 0.023), 0, True),        # square under the cup, its top face 3 mm away
    ((0.0, 0.0, 0.028), 20, False),      # its highest edge 2.4 mm from the cup face, but 20 degrees off square
    ((0.0, 0.0, 0.027), 0, False),       # 7 mm away: out of reach
    ((0.015, 0.0, 0.023), 0, False),     # 15 mm off the cup's axis
])
def test_what_the_cup_takes(cell, offset, tilt_deg, picked) -> None:
    """A part put (teleported) under the cup; suction on: one tick decides, before it falls."""
    world, ctl, loop = cell
    move_to(loop, ctl, (-0.3, 0.1, 0.15))
    face = ctl.snapshot.actual_TCP_pose[:3]
    cube = world.cubes[0]
    world.p.resetBasePositionAndOrientation(cube, (face[0] + offset[0], face[1] + offset[1], face[2] - offset[2]),
                                            world.p.getQuaternionFromEuler((np.radians(tilt_deg), 0, 0)))
    suction(ctl, True)
    loop.tick()
    assert held(ctl) == picked


def test_a_vacuum_fault_ignores_the_output(cell) -> None:
    world, ctl, loop = cell
    move_to(loop, ctl, (-0.45, -0.1, 0.042))
    ok, _ = ctl.trigger_fault("vacuum_fault")
    assert ok and ctl.faults.active("vacuum_fault")
    suction(ctl, True)
    run(loop, 0.1)
    assert not held(ctl)
    ctl.trigger_fault("reset")
    run(loop, 0.1)
    assert held(ctl)


def test_release_into_a_pocket_rests_in_it() -> None:
    world, ctl, loop = vacuum_cell([[-0.45, -0.1]], [{"name": "out", "kind": "fixture", "pockets": [[-0.40, 0.10]]}])
    try:
        run(loop, 0.3)
        move_to(loop, ctl, (-0.45, -0.1, 0.042))
        suction(ctl, True)
        run(loop, 0.1)
        assert held(ctl)
        move_to(loop, ctl, (-0.45, -0.1, 0.15))
        move_to(loop, ctl, (-0.40, 0.10, 0.15))
        move_to(loop, ctl, (-0.40, 0.10, 0.050))  # the cube's bottom 4 mm above the plate
        suction(ctl, False)
        run(loop, 1.0)
        pos, _ = world.p.getBasePositionAndOrientation(world.cubes[0])
        np.testing.assert_allclose(pos, (-0.40, 0.10, 0.026), atol=2e-3)
    finally:
        world.close()
