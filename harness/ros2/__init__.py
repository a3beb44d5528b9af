"""ROS 2 for the ``ros2`` extra (rclpy from the ``ros-jazzy-*`` wheels).

A live ROS 2 graph beside a run: every recorded topic published from its CDR bytes, external
nodes' outputs taken back in lockstep (:mod:`~harness.ros2.bridge`), a ROS_DOMAIN_ID per run
(:mod:`~harness.ros2.domain`) and the external processes' lifecycle
(:mod:`~harness.ros2.processes`). :mod:`~harness.ros2.tf2_msgs` makes ``tf2_msgs``
(``/tf``, ``/tf_static``), which the wheels lack, available to rclpy, built by
:mod:`~harness.ros2.rosidl_build` with the wheels' rosidl tools; :mod:`~harness.ros2.errors`
holds the error. Importing this package imports neither rclpy nor the generators.
"""

__all__: list[str] = []
