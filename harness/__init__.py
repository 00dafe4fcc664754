"""fmpy harness for the SuperTwistingObserver FMU and its closed-loop bench."""
