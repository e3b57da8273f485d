"""Backends behind one contract (base.py): the MuJoCo twin and the Dynamixel chain."""
