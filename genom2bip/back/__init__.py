"""Back ends: the BIP model as text (BIP2 source) and as runnable Python."""
