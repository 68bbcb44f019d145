"""One module per `tmeye` sub-command; each exposes `register(subparsers)`."""
