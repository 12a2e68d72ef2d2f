"""mavlink_gateway"""
