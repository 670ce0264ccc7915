"""Property-based fuzzing (hypothesis) of the public constructors and step/predict."""
