"""rosapi: ROS graph and parameter introspection served as /rosapi/* services (rosbridge companion)."""
