"""Control: the safety layer, run metrics and the fixed-rate runner."""
