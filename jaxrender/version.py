"""The package version, apart from __init__ so that any module can read it without importing
the whole API."""

VERSION = "0.1.0"
