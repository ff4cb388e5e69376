"""The root of every error particlebot raises, so that a script can catch them all at once.

    ParticlebotError
"""


class ParticlebotError(Exception):
    """Base class of every error the particlebot package raises on purpose."""
