"""mavlink"""
