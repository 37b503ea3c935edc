"""The Macro B controller of the virtual machine: parser, variables,
expressions, execution, motion.
"""
