"""rayvr benchmarks: `python -m benchmarks NAME [--quick] [options]` (see harness.py)."""
