"""The LinuxCNC controller of the virtual machine: an rs274ngc interpreter (parse,
o-word structure, expressions and comment text, parameters, execution) driving the
Macro B control's motion with LinuxCNC's G codes.
"""
