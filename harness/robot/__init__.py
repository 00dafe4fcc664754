"""Serial robots: URDF reading, rigid-body dynamics (the C core), identification."""
