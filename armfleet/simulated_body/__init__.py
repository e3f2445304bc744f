"""What PyBullet simulates of an arm: its lean URDF and the link pairs that can touch."""
