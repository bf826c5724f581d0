"""hearsee.stream"""
