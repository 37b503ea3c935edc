"""The virtual machine: interpreters that run emitted program text as a controller would."""
