"""TODO: door sign."""
