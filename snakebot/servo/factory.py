"""What a servo answers as straight from the factory (or after a Factory Reset).

X-series servos all leave the factory as ID 1 at 57600 bit/s (the ID register's default 1 and the
Baud Rate register's default index 1). The control-table data says the same per model; the unit
test over every supported table keeps the two from drifting apart.
"""

FACTORY_ID = 1
"""The ID a factory-fresh servo answers as."""

FACTORY_BAUD = 57600
"""The baud rate (bit/s) of a factory-fresh servo."""
