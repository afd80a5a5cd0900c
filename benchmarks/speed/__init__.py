"""Throughput: env steps, training samples/s, the PPO update, rollout capture, cold starts, video, learners."""
