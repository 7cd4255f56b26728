"""The commissioning engineer's tools (issue 26): the ROS log kept on the server side (log_history.py), so the
page shows the last minutes when it opens, not only what arrives from then on. No ROS here."""
