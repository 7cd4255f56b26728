"""Simulated UR5 robot cell (PyBullet) that impersonates a Universal Robots controller.

See docs/sim.md. Entry point: ``python -m sim --host 127.0.0.2``.
"""
