"""hearsee.sim"""
