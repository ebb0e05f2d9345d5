"""The learner: the Q-networks and their action rules, the task's lockstep step with its rewards,
replay, the jitted training iteration, its checkpoints, sharding over devices and the run's logs."""
