"""Alarms: the pure rule engine (conditions, lifecycle, flood) and the device-fault conditions."""
