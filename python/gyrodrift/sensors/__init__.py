"""Sensor noise characterisation: Allan deviation of the IMU axes and its noise terms."""
