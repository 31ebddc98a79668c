"""Co-simulation: the master that drives FMUs under sampled controllers, the communication-step study, plots."""
