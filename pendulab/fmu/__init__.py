"""FMU export, validation and co-simulation."""
