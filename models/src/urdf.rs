//! Loading robots from URDF plus a side file (TOML/JSON) with capsules and acceleration/jerk limits.
