"""MJX tabletop scenes: objects, gripper, primitives, cameras and scenarios."""
