"""What every physics engine shares: the interface, the run protocol and the generated
model files."""
