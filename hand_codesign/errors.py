"""Errors every part of hand_codesign shares."""


class UserError(Exception):
    """A mistake of the user's (bad file, bad flag): printed as one clear line, no traceback."""
