"""Inputs: what a user hands cgamesh, read and validated into specs (scene files and their rendering keys)."""
