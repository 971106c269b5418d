"""regrasp.envelope.finger_envelope."""
