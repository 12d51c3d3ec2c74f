"""The error of the ROS 2 profile: a ROS 2 name, message or peer REI cannot use.

Raised for a malformed name or option given by the user (with what was expected and what
was found), and for a message on the wire that does not follow rmw_zenoh's format. A ROS 2
stack that misbehaves *during* a run is not an exception to the run: the adapter turns it
into a goal state or a held command, and the run's verdict says what happened.

Every stage has an errors.py of its own (one error class per stage, all under
``rei.lang.errors.ReiError``, as STYLE.md asks), so this file name repeats on purpose.
"""

from rei.lang.errors import ReiError


class Ros2Error(ReiError):
    """A ROS 2 name, option or wire message is not what rmw_zenoh_cpp's format expects."""
