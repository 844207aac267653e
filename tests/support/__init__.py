"""What tests, benchmarks and docs share: helpers, generated families and the
fixed problems checked in under tests/data (tests/README.md)."""
