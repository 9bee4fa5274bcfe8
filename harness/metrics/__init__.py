"""Metrics, one public function per module. Lengths are divided by the clean mesh's
bounding-box diagonal by the caller (`harness.measure`), angles are in degrees."""
