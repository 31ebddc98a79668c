"""Analysis of the model: equilibria, exact linearization, modes."""
