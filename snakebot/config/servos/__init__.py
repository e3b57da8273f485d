"""Servo files (``firmware_configs/servos/<model>.toml``): the file, its settings table and the
twin's optional servo-model parts."""
