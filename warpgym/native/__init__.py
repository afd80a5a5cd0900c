"""Each family's tasks outside warpgym, the judge of its physics and its policies: ``robots`` (warpgym's Ant and
Humanoid in native MuJoCo, from the same MJCF), ``suite`` (Gymnasium's own envs, step for step and episode by
episode), ``legged`` (a legged policy in native MuJoCo over a fixed schedule of commands)."""
