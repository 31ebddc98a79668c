"""Controllers for the double pendulum (LQR balance, swing-up, tracking)."""
