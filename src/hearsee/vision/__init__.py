"""hearsee.vision"""
