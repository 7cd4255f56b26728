"""/sim/restock's world side: parts back where they lay at the start, except one a robot holds or touches."""
import numpy as np

from sim.world import World, restock_text


def test_restock_puts_back_every_part_no_robot_touches() -> None:
    world = World(seed=0)
    try:
        p = world.p
        homes = world.body_poses()
        moved_away = (0.35, 0.3, 0.02)
        p.resetBasePositionAndOrientation(world.cubes[0], moved_away, p.getQuaternionFromEuler((0, 0, 0.7)))
        # A part between the fingers: where the left finger is.
        finger = p.getLinkState(world.arms[0].robot, world.arms[0].finger_links[0])[0]
        p.resetBasePositionAndOrientation(world.cubes[1], finger, (0, 0, 0, 1))
        p.performCollisionDetection()
        assert p.getContactPoints(bodyA=world.cubes[1], bodyB=world.arms[0].robot), "the part touches the gripper"

        assert world.restock() == (2, 1)
        after = world.body_poses()
        assert np.allclose(after[0][0], homes[0][0], atol=1e-9) and np.allclose(after[0][1], homes[0][1], atol=1e-9)
        assert np.allclose(after[1][0], finger, atol=1e-9), "the touched part stays where it is"
        assert np.allclose(after[2][0], homes[2][0], atol=1e-9)
    finally:
        world.close()


def test_restock_answer() -> None:
    assert restock_text(3, 0) == "3 parts put back"
    assert restock_text(1, 1) == "1 part put back; 1 left where it is: a robot holds or touches it"
    assert restock_text(0, 2) == "0 parts put back; 2 left where they are: a robot holds or touches them"
