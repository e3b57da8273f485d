"""pyserial URL handlers of snakebot (found through `serial.protocol_handler_packages`)."""
