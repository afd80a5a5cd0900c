"""Physics: trained policies replayed at finer steps and in native MuJoCo, the suite against Gymnasium's envs."""
