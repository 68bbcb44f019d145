"""Thin routers: parse, call a service, answer. One module per area."""
