"""The cone engine: 3-D shakedown bounds on second-order friction cones (MODEL.md s.8.3)."""
