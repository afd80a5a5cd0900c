"""Learning: Gymnasium's suite trained to the published figures, preset sweeps, SB3 beside warpgym, v4 against v5,
the spread over seeds."""
