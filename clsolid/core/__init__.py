"""What every synthesis method shares: OpenCL device selection and probing, program
building, the Philox random streams and the conflict-free update schedule."""
