"""Package data: gazebo (jinja2 templates / XML schemas); no code."""
